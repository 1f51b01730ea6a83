// contact_lab: reproducers and measurements for contacts, rest and sleep (issue 11). Not part of
// the product: built only with -DSOFTBODY_BUILD_EXP=ON (exp/CMakeLists.txt).
// Usage: contact_lab SCENARIO [key=value ...]; threads=N fixes the pool's thread count (runs are
// bit-identical only for the same N). `scene path=FILE` also takes T= (seconds), sub=, sleep=0|1,
// nodamp=1, every=, who=1, bodies=1 (or track=NAME: the bodies whose names hold NAME) and spike=1
// (after 4 s, every body's fastest particle in each step where one moves ≥ 8 mm/s: which particle
// pops, and where), stillness=1 (every `every` steps, which bodies restarted the test of rest and
// the median rise of the bodies' centres: StillnessCensus); late_at=T with late_roll=, late_sub=,
// late_mu= (colliders), late_bmu= (body–body), late_damping=, late_alpha= (soft bodies) changes
// those from T on; plastic_until=T stops plastic flow at T, keeping what flowed. `overlap` takes
// trace=1 (both bodies' speed and spin at every step).
#include <Eigen/Dense>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "sim/base/parallel.h"
#include "sim/mesh/mesh_io.h"
#include "sim/scene/scene.h"
#include "sim/world/sleep_phase.h"
#include "sim/world/world.h"

using namespace sb;

namespace {

std::map<std::string, std::string> opt;
double num(const std::string& k, double def) {
  auto it = opt.find(k);
  return it == opt.end() ? def : std::atof(it->second.c_str());
}
std::string str(const std::string& k, const std::string& def) {
  auto it = opt.find(k);
  return it == opt.end() ? def : it->second;
}
bool has(const std::string& k) {
  return opt.count(k) > 0;
}

struct Shape {
  std::vector<Vec3> points;
  std::vector<std::array<int, 3>> tris;
};

// Closed box surface, n×n quads per face, centred at the origin, edges `size`.
Shape box(const Vec3& size, int n) {
  Shape s;
  std::map<std::array<int, 3>, int> index;
  auto vertex = [&](const Eigen::Vector3i& q) {
    const std::array<int, 3> key{q.x(), q.y(), q.z()};
    auto it = index.find(key);
    if (it != index.end()) return it->second;
    s.points.push_back((q.cast<double>() / n - Vec3::Constant(0.5)).cwiseProduct(size));
    return index[key] = int(s.points.size()) - 1;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          auto at = [&](int a, int b) {
            Eigen::Vector3i q;
            q[axis] = side * n;
            q[u] = a;
            q[v] = b;
            return vertex(q);
          };
          const int c00 = at(i, j), c10 = at(i + 1, j), c11 = at(i + 1, j + 1), c01 = at(i, j + 1);
          if (side == 1) {
            s.tris.push_back({c00, c10, c11});
            s.tris.push_back({c00, c11, c01});
          } else {
            s.tris.push_back({c00, c11, c10});
            s.tris.push_back({c00, c01, c11});
          }
        }
    }
  return s;
}

// A mesh file's shape scaled so its largest bounding-box extent is `size`, centred at the origin
// of its box. `name` is a cage in assets/meshes (bunny, suzanne, box, bar) or a path.
Shape meshShape(const std::string& name, double size) {
  const std::string path = name.find('/') != std::string::npos
                               ? name
                               : std::string(SOFTBODY_ASSET_DIR) + "/meshes/" + name + "_cage.obj";
  const mesh::TriangleMesh m = mesh::readMesh(path);
  Eigen::AlignedBox3d bb;
  for (const Vec3& v : m.vertices) bb.extend(v);
  const double scale = size / bb.sizes().maxCoeff();
  Shape s;
  for (const Vec3& v : m.vertices) s.points.push_back(scale * (v - bb.center()));
  s.tris = m.triangles;
  return s;
}

Shape shapeOf(const std::string& kind, double size) {
  if (kind == "cube") return box(Vec3::Constant(size), int(num("n", 4)));
  return meshShape(kind, size);
}

Mat3 rotXYZ(double ax, double ay, double az) {
  const double d = M_PI / 180;
  return (Eigen::AngleAxisd(az * d, Vec3::UnitZ()) * Eigen::AngleAxisd(ay * d, Vec3::UnitY()) *
          Eigen::AngleAxisd(ax * d, Vec3::UnitX()))
      .toRotationMatrix();
}

BodyDef makeBody(const Shape& s, const Vec3& at, const Mat3& R, const std::string& mode,
                 double alpha, double beta, double damping, double mass,
                 const std::string& name = "b") {
  BodyDef def;
  def.name = name;
  for (const Vec3& p : s.points) def.positions.push_back(at + R * p);
  def.surface = s.tris;
  parseMode(mode, &def.params.mode);
  def.params.alpha = alpha;
  def.params.beta = beta;
  def.params.damping = damping;
#ifndef LAB_BASELINE
  def.params.restitution = num("be", 0.0);
#endif
  def.totalMass = mass;
  return def;
}

double minY(const Shape& s, const Mat3& R) {
  double m = 1e30;
  for (const Vec3& p : s.points) m = std::min(m, (R * p).y());
  return m;
}

void applyWorldOptions(WorldSettings& ws) {
  if (has("dt")) ws.timeStep = num("dt", 1.0 / 60);
  if (has("sub")) ws.substeps = int(num("sub", 4));
  if (has("bmu")) ws.contactFriction = num("bmu", 0.5);
#ifndef LAB_BASELINE
  if (has("ethr")) ws.restitutionThreshold = num("ethr", 1.0);
  if (has("sleep")) ws.sleep = num("sleep", 1) != 0;
  if (has("roll")) ws.rollingResistance = num("roll", 0.05);
  if (has("maxsub")) ws.maxSubstep = num("maxsub", 1.0 / 120);
#endif
}

WorldSettings settingsFromOptions() {
  WorldSettings ws;
  ws.timeStep = 1.0 / 60;
  ws.substeps = 4;
  ws.gravity = Vec3(0, -num("g", 9.81), 0);
#ifndef LAB_BASELINE
  ws.sleep = false;  // measurements see the motion itself unless sleep=1
#endif
  applyWorldOptions(ws);
  return ws;
}

Collider floorCollider(const Vec3& normal = Vec3::UnitY()) {
  Collider c = Collider::plane(normal, 0, num("mu", 0.6));
#ifndef LAB_BASELINE
  c.restitution = num("e", 0);
#endif
  return c;
}

// ---- measurements ---------------------------------------------------------------------------
double kinetic(const World& w) {
  double e = 0;
  for (BodyHandle b : w.bodies()) {
    const Eigen::VectorXf m = w.masses(b);
    e += 0.5 *
         (m.cast<double>().array() * w.velocities(b).cast<double>().rowwise().squaredNorm().array())
             .sum();
  }
  return e;
}
double potential(const World& w) {
  double e = 0;
  for (BodyHandle b : w.bodies()) e -= w.mass(b) * w.settings().gravity.dot(w.centreOfMass(b));
  return e;
}
double maxSpeed(const World& w) {
  double s = 0;
  for (BodyHandle b : w.bodies())
    s = std::max(s, double(w.velocities(b).rowwise().norm().maxCoeff()));
  return s;
}
double sumMV(const World& w) {
  double s = 0;
  for (BodyHandle b : w.bodies()) {
    const Eigen::VectorXf m = w.masses(b);
    s += (m.cast<double>().array() * w.velocities(b).cast<double>().rowwise().norm().array()).sum();
  }
  return s;
}
Vec3 momentum(const World& w) {
  Vec3 p = Vec3::Zero();
  for (BodyHandle b : w.bodies()) p += w.linearMomentum(b);
  return p;
}
int sleepingCount(const World& w) {
  int n = 0;
#ifndef LAB_BASELINE
  for (BodyHandle b : w.bodies()) n += w.isSleeping(b);
#else
  (void)w;
#endif
  return n;
}
// Which bodies keep a pile awake: the test of rest of sleep_phase.h, run once per step on every
// body whether it sleeps or not (every particle within its sleep speed × kTimeToSleep of where
// the count started, for kTimeToSleep; the radius from the body's box at the start, as
// body_model.cpp takes it). report() prints, for the steps since the last report: the bodies
// not ready, how many restarted their count, the eight that restarted most (with the farthest a
// particle strayed, in radii), and the median rise of the bodies' centres (mm; a pile at rest
// neither rises nor sinks). An island sleeps only when none of its bodies restarts for
// kTimeToSleep.
class StillnessCensus {
 public:
  explicit StillnessCensus(const World& w) : bodies_(w.bodies()) {
    for (BodyHandle b : bodies_) {
      const Eigen::MatrixX3f x = w.positions(b);
      const double diagonal = (x.colwise().maxCoeff() - x.colwise().minCoeff()).norm();
      Body s;
      s.radius = std::min(0.05, 0.05 * diagonal) * kTimeToSleep;
      s.anchor = x;
      s.height = w.centreOfMass(b).y();
      body_.push_back(s);
    }
  }
  void observe(const World& w) {
    for (size_t i = 0; i < bodies_.size(); ++i) {
      Body& s = body_[i];
      const Eigen::MatrixX3f x = w.positions(bodies_[i]);
      const double far = (x - s.anchor).rowwise().norm().maxCoeff();
      if (far > s.radius) {
        s.anchor = x;
        s.still = 0;
        ++s.restarts;
        s.farthest = std::max(s.farthest, far / s.radius);
      } else {
        s.still += w.settings().timeStep;
      }
    }
  }
  void report(const World& w) {
    int notReady = 0;
    std::vector<std::pair<int, int>> restarted;  // (restarts, body)
    std::vector<double> rise;
    for (size_t i = 0; i < bodies_.size(); ++i) {
      Body& s = body_[i];
      notReady += s.still < kTimeToSleep ? 1 : 0;
      if (s.restarts > 0) restarted.push_back({s.restarts, int(i)});
      const double height = w.centreOfMass(bodies_[i]).y();
      rise.push_back(height - s.height);
      s.height = height;
    }
    std::nth_element(rise.begin(), rise.begin() + long(rise.size() / 2), rise.end());
    std::sort(restarted.rbegin(), restarted.rend());
    std::printf("%6.2f not ready %d, restarted %zu, median rise %+.3f mm:", w.time(), notReady,
                restarted.size(), rise.empty() ? 0.0 : 1e3 * rise[rise.size() / 2]);
    for (size_t j = 0; j < std::min<size_t>(restarted.size(), 8); ++j) {
      const Body& s = body_[size_t(restarted[j].second)];
      std::printf(" [%s x%d %.1fr]", w.name(bodies_[size_t(restarted[j].second)]).c_str(),
                  restarted[j].first, s.farthest);
    }
    std::printf("\n");
    for (Body& s : body_) {
      s.restarts = 0;
      s.farthest = 0;
    }
  }

 private:
  struct Body {
    double radius = 0;  // m
    Eigen::MatrixX3f anchor;
    double still = 0;   // s
    double height = 0;  // the centre's height at the last report (m)
    int restarts = 0;   // since the last report
    double farthest = 0;
  };
  std::vector<BodyHandle> bodies_;
  std::vector<Body> body_;
};
// RMS distance of particles from the centre of mass.
double rmsSize(const World& w, BodyHandle b) {
  const Eigen::MatrixX3d x = w.positions(b).cast<double>();
  const Vec3 c = w.centreOfMass(b);
  return std::sqrt((x.rowwise() - c.transpose()).rowwise().squaredNorm().mean());
}
// Largest relative change of a pairwise distance vs `rest`.
double pairError(const World& w, BodyHandle b, const Eigen::MatrixX3d& rest) {
  const Eigen::MatrixX3d x = w.positions(b).cast<double>();
  double worst = 0;
  for (int i = 0; i < x.rows(); ++i)
    for (int j = i + 1; j < x.rows(); ++j) {
      const double d0 = (rest.row(i) - rest.row(j)).norm();
      if (d0 < 1e-9) continue;
      worst = std::max(worst, std::abs((x.row(i) - x.row(j)).norm() - d0) / d0);
    }
  return worst;
}

// Generalised winding number of p w.r.t. a closed surface.
double winding(const Vec3& p, const Eigen::MatrixX3d& x, const std::vector<std::array<int, 3>>& t) {
  double sum = 0;
  for (const auto& tri : t) {
    const Vec3 a = x.row(tri[0]).transpose() - p, b = x.row(tri[1]).transpose() - p,
               c = x.row(tri[2]).transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double nm = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    sum += 2 * std::atan2(nm, den);
  }
  return sum / (4 * M_PI);
}
double triDist(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double nn = n.squaredNorm();
  auto seg = [&](const Vec3& u, const Vec3& v) {
    const Vec3 d = v - u;
    const double t = std::clamp((p - u).dot(d) / std::max(d.squaredNorm(), 1e-30), 0.0, 1.0);
    return (p - (u + t * d)).norm();
  };
  double best = std::min({seg(a, b), seg(b, c), seg(c, a)});
  if (nn > 0) {
    const Vec3 q = p - (p - a).dot(n) / nn * n;
    const double w0 = (b - q).cross(c - q).dot(n), w1 = (c - q).cross(a - q).dot(n),
                 w2 = (a - q).cross(b - q).dot(n);
    if (w0 >= 0 && w1 >= 0 && w2 >= 0)
      best = std::min(best, std::abs((p - a).dot(n)) / std::sqrt(nn));
  }
  return best;
}
double meanEdge(const Shape& s) {
  double sum = 0;
  int n = 0;
  for (const auto& t : s.tris)
    for (int k = 0; k < 3; ++k) {
      sum += (s.points[size_t(t[size_t(k)])] - s.points[size_t(t[size_t((k + 1) % 3)])]).norm();
      ++n;
    }
  return sum / n;
}
// Deepest particle of any body inside any other body, relative to the other body's spacing.
double deepestPenetration(const World& w, const std::vector<Shape>& shapes, double* metres) {
  const auto bodies = w.bodies();
  double deepest = 0, deepestM = 0;
  for (size_t i = 0; i < bodies.size(); ++i) {
    const Eigen::MatrixX3d xi = w.positions(bodies[i]).cast<double>();
    for (size_t j = 0; j < bodies.size(); ++j) {
      if (i == j) continue;
      const Eigen::MatrixX3d xj = w.positions(bodies[j]).cast<double>();
      Eigen::AlignedBox3d bb;
      for (int k = 0; k < xj.rows(); ++k) bb.extend(Vec3(xj.row(k).transpose()));
      const double spacing = std::min(meanEdge(shapes[i]), meanEdge(shapes[j]));
      for (int k = 0; k < xi.rows(); ++k) {
        const Vec3 p = xi.row(k).transpose();
        if (!bb.contains(p)) continue;
        if (std::abs(winding(p, xj, shapes[j].tris)) < 0.5) continue;
        double d = 1e30;
        for (const auto& t : shapes[j].tris)
          d = std::min(d, triDist(p, xj.row(t[0]).transpose(), xj.row(t[1]).transpose(),
                                  xj.row(t[2]).transpose()));
        if (d / spacing > deepest) {
          deepest = d / spacing;
          deepestM = d;
        }
      }
    }
  }
  if (metres) *metres = deepestM;
  return deepest;
}

int stepsFor(const World& w, double T) {
  return int(std::lround(T / w.settings().timeStep));
}

double cpuSeconds() {
  return double(std::clock()) / CLOCKS_PER_SEC;
}

// ---- scenarios ------------------------------------------------------------------------------

// A soft body resting on the floor, a rigid box on top, both dropped at v0.
int softRigid() {
  const double L = num("L", 0.55), T = num("T", 20), v0 = num("v0", 4);
  World w(settingsFromOptions());
  w.addCollider(floorCollider());
  const Shape soft = shapeOf(str("soft", "suzanne"), L);
  const Shape top = shapeOf(str("top", "cube"), num("topL", 0.5 * L));
  const Mat3 I = Mat3::Identity();
  const double y0 = -minY(soft, I) + 0.01 * L;
  double softTop = -1e30;
  for (const Vec3& p : soft.points) softTop = std::max(softTop, p.y());
  BodyDef a = makeBody(soft, Vec3(0, y0, 0), I, str("mode", "linear"), num("alpha", 0.6),
                       num("beta", 0.3), num("damping", 0), num("mass", 1.0), "soft");
  a.velocity = Vec3(0, -v0, 0);
  BodyDef b = makeBody(top, Vec3(0, y0 + softTop - minY(top, I) + 0.01 * L, 0), I,
                       str("topmode", "rigid"), num("topalpha", 1), 0,
                       num("topdamping", num("damping", 0)), num("topmass", 1.0), "top");
  b.velocity = Vec3(0, -v0, 0);
  BodyHandle ha = w.addBody(a), hb = ha;
  if (num("notop", 0) == 0) hb = w.addBody(b);
  const double size0 = rmsSize(w, ha);
  const int steps = stepsFor(w, T);
  const int every = int(num("every", std::max(1, steps / 20)));
  double peakLate = 0, lastAwake = 0, maxSize = 0;
  std::printf("t(s)  maxSpeed(m/s)  KE(J)  softSize/rest  topY(m) sleeping\n");
  for (int s = 1; s <= steps; ++s) {
    w.step();
    if (w.time() > 3.0) peakLate = std::max(peakLate, maxSpeed(w));
    if (maxSpeed(w) >= 0.01) lastAwake = w.time();
    maxSize = std::max(maxSize, rmsSize(w, ha) / size0);
    if (s % every == 0 || s == steps)
      std::printf("%6.2f %10.4g %10.4g %8.4f %8.4f %d\n", w.time(), maxSpeed(w), kinetic(w),
                  rmsSize(w, ha) / size0, w.centreOfMass(hb).y(), sleepingCount(w));
  }
  std::printf(
      "max particle speed after 3 s: %.4g m/s; last time any particle >= 1 cm/s: %.3f s; "
      "largest soft size/rest %.4f\n",
      peakLate, lastAwake, maxSize);
  return 0;
}

// N bodies dropped into a pen (four static boxes).
int pile() {
  const int N = int(num("N", 18));
  const double L = num("L", 0.5), T = num("T", 20);
  World w(settingsFromOptions());
  const double mu = num("mu", 0.6);
  const double half = num("pen", 1.5 * L + 0.1);
  w.addCollider(floorCollider());
  const double H = 10 * L;
  w.addCollider(
      Collider::box(Vec3(half + 0.1, H, 0), Vec3(0.1, H, half + 0.2), Mat3::Identity(), mu));
  w.addCollider(
      Collider::box(Vec3(-half - 0.1, H, 0), Vec3(0.1, H, half + 0.2), Mat3::Identity(), mu));
  w.addCollider(
      Collider::box(Vec3(0, H, half + 0.1), Vec3(half + 0.2, H, 0.1), Mat3::Identity(), mu));
  w.addCollider(
      Collider::box(Vec3(0, H, -half - 0.1), Vec3(half + 0.2, H, 0.1), Mat3::Identity(), mu));
  const char* kinds[3] = {"bunny", "suzanne", "cube"};
  const char* modes[3] = {"rigid", "linear", "quadratic"};
  std::vector<Shape> shapes;
  const double damping = num("damping", 0);
  std::vector<double> size0;
  for (int i = 0; i < N; ++i) {
    const int layer = i / 3, col = i % 3;
    const Shape s = shapeOf(kinds[(i + layer) % 3], L);
    const std::string mode = num("allrigid", 0) > 0 ? "rigid" : modes[(i / 2) % 3];
    const double alpha = mode == "rigid" ? 1.0 : num("alpha", 0.5);
    const Mat3 R = rotXYZ(7 * i, 31 * i, 13 * i);
    BodyDef d =
        makeBody(s, Vec3((col - 1) * (L + 0.05), 0.6 * L + layer * 1.15 * L, 0.05 * (i % 2)), R,
                 mode, alpha, 0.5, damping, 1.0);
    shapes.push_back(s);
    size0.push_back(rmsSize(w, w.addBody(d)));
  }
  const int steps = stepsFor(w, T);
  const int every = int(num("every", std::max(1, steps / 20)));
  const double dropSpeed = std::sqrt(2 * 9.81 * (0.6 * L + (N / 3 - 1) * 1.15 * L));
  double peak = 0, peakLate = 0, lastAwake = 0, growth = 0, lastSleepAll = -1;
  std::printf("drop speed bound %.3g m/s\nt(s)  maxSpeed  KE(J)  KE+PE(J) sleeping\n", dropSpeed);
  const double cpu0 = cpuSeconds();
  for (int s = 1; s <= steps; ++s) {
    w.step();
    const double v = maxSpeed(w);
    peak = std::max(peak, v);
    if (w.time() > T - 5) peakLate = std::max(peakLate, v);
    if (v >= 0.01) lastAwake = w.time();
    const int sleeping = sleepingCount(w);
    if (sleeping == N && lastSleepAll < 0) lastSleepAll = w.time();
    if (sleeping < N) lastSleepAll = -1;
    const auto bs = w.bodies();
    for (size_t i = 0; i < bs.size(); ++i) growth = std::max(growth, rmsSize(w, bs[i]) / size0[i]);
    if (s % every == 0 || s == steps) {
      std::printf("%6.2f %10.4g %10.4g %10.4g %d", w.time(), v, kinetic(w),
                  kinetic(w) + potential(w), sleeping);
      if (num("who", 0) > 0) {  // the fastest body: index, mode, its fastest particle's height
        size_t f = 0;
        double fv = -1;
        Eigen::Index fi = 0;
        for (size_t i = 0; i < bs.size(); ++i) {
          Eigen::Index at = 0;
          const double bv = w.velocities(bs[i]).rowwise().norm().maxCoeff(&at);
          if (bv > fv) {
            fv = bv;
            f = i;
            fi = at;
          }
        }
        std::printf("  fastest body %zu (%s) particle %ld at y %.3f, centre v %.4f m/s", f,
                    modeName(w.params(bs[f]).mode), long(fi), w.positions(bs[f])(fi, 1),
                    (w.linearMomentum(bs[f]) / w.mass(bs[f])).norm());
      }
      std::printf("\n");
    }
    if (!std::isfinite(v) || v > 1e3) {
      std::printf("blew up at step %d\n", s);
      break;
    }
    for (auto& e : w.takeEvents()) std::printf("event: %s\n", e.message.c_str());
  }
  std::printf(
      "peak speed %.4g m/s (drop bound %.3g), peak in last 5 s %.4g m/s, last time >= 1 cm/s "
      "%.3f s, all asleep from %.2f s, largest body size/rest %.4f, CPU %.2f s\n",
      peak, dropSpeed, peakLate, lastAwake, lastSleepAll, growth, cpuSeconds() - cpu0);
  if (num("pen_check", 1)) {
    double m = 0;
    const double d = deepestPenetration(w, shapes, &m);
    std::printf("deepest penetration at end: %.4g spacings (%.3g m)\n", d, m);
  }
  return 0;
}

// One body at rest on a floor tilted by `slope` degrees (about z), friction mu.
int rest() {
  const double L = num("L", 0.4), T = num("T", 10), slope = num("slope", 0);
  World w(settingsFromOptions());
  const Mat3 R = rotXYZ(0, num("yaw", 0), slope);
  const Vec3 n = R * Vec3::UnitY();
  w.addCollider(floorCollider(n));
  const Shape s = shapeOf(str("kind", "cube"), L);
  const Mat3 Rb = R * rotXYZ(num("rx", 0), num("ry", 0), num("rz", 0));
  const double h =
      -minY(s, rotXYZ(num("rx", 0), num("ry", 0), num("rz", 0))) + num("lift", 0.0005 * L);
  BodyDef d = makeBody(s, h * n, Rb, str("mode", "rigid"), num("alpha", 1), num("beta", 0),
                       num("damping", 0), num("mass", 1));
  BodyHandle b = w.addBody(d);
  const Vec3 c0 = w.centreOfMass(b);
  const double size0 = rmsSize(w, b);
  const int steps = stepsFor(w, T);
  const int every = int(num("every", std::max(1, steps / 10)));
  double settleFrom = -1;
  std::printf("t(s)  drift(m)  dx dy dz (m)  maxSpeed(m/s)  size/rest asleep\n");
  for (int k = 1; k <= steps; ++k) {
    w.step();
    if (w.time() >= 1.0 && settleFrom < 0) settleFrom = 0;
    if (k % every == 0 || k == steps) {
      const Vec3 dd = w.centreOfMass(b) - c0;
      const Vec3 tang = dd - dd.dot(n) * n;
      std::printf("%6.2f %10.4g  %+.4g %+.4g %+.4g  %10.4g %8.5f %d\n", w.time(), tang.norm(),
                  dd.x(), dd.y(), dd.z(), maxSpeed(w), rmsSize(w, b) / size0, sleepingCount(w));
    }
  }
  const Vec3 dd = w.centreOfMass(b) - c0;
  std::printf("drift along the slope after %.0f s: %.4g m\n", T, (dd - dd.dot(n) * n).norm());
  return 0;
}

// A stack of n bodies, each L, on the floor.
int stack() {
  const int n = int(num("N", 5));
  const double L = num("L", 0.4), T = num("T", 60);
  World w(settingsFromOptions());
  w.addCollider(floorCollider());
  const Shape s = shapeOf(str("kind", "cube"), L);
  std::vector<BodyHandle> hs;
  const double gapFrac = num("gapfrac", 0.02);
  double bottom = 0.001 * L - minY(s, Mat3::Identity());
  for (int i = 0; i < n; ++i) {
    BodyDef d = makeBody(s, Vec3(0, bottom + i * L * (1 + gapFrac), 0), Mat3::Identity(),
                         str("mode", "rigid"), num("alpha", 1), num("beta", 0.2), num("damping", 0),
                         num("mass", 1));
    hs.push_back(w.addBody(d));
  }
  std::vector<Vec3> c0;
  for (auto h : hs) c0.push_back(w.centreOfMass(h));
  const int steps = stepsFor(w, T);
  const int every = int(num("every", std::max(1, steps / 12)));
  std::printf("t(s)  top drift (m, horizontal)  top dy  maxSpeed  KE  sleeping\n");
  double worst = 0;
  for (int k = 1; k <= steps; ++k) {
    w.step();
    const Vec3 d = w.centreOfMass(hs.back()) - c0.back();
    worst = std::max(worst, std::hypot(d.x(), d.z()));
    if (num("trace", 0) > 0 && w.time() >= num("trace", 0) && w.time() < num("trace", 0) + 0.25) {
      // Every step for 0.25 s: each body's centre velocity and spin, and the deepest contact.
      std::printf("%7.4f deepest %.3g", w.time(), w.lastDeepestContact());
      for (auto h : hs) {
        const Vec3 vc = w.linearMomentum(h) / w.mass(h);
        const Vec3 c = w.centreOfMass(h);
        Mat3 I = Mat3::Zero();
        const Eigen::VectorXf m = w.masses(h);
        for (int i = 0; i < int(m.size()); ++i) {
          const Vec3 r = w.positions(h).row(i).cast<double>().transpose() - c;
          I += m[i] * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
        }
        const Vec3 om = I.ldlt().solve(w.angularMomentum(h, c));
        std::printf(" | v %+.2e %+.2e %+.2e w %+.2e %+.2e %+.2e vmax %.2e", vc.x(), vc.y(), vc.z(),
                    om.x(), om.y(), om.z(), w.velocities(h).rowwise().norm().maxCoeff());
      }
      std::printf("\n");
    }
    if (k % every == 0 || k == steps) {
      std::printf(
          "%6.2f %10.4g (%.3f%% of L) %+.4g %10.4g %10.4g %d deepest %.3g dx %+.3g dz %+.3g",
          w.time(), std::hypot(d.x(), d.z()), 100 * std::hypot(d.x(), d.z()) / L, d.y(),
          maxSpeed(w), kinetic(w), sleepingCount(w), w.lastDeepestContact(), d.x(), d.z());
      if (num("all", 0) > 0)
        for (size_t i = 0; i < hs.size(); ++i) {
          const Vec3 di = w.centreOfMass(hs[i]) - c0[i];
          std::printf(" | %zu: %+.3g %+.3g %+.3g", i, di.x(), di.y(), di.z());
        }
      std::printf("\n");
    }
  }
  std::printf("top drift: end %.4g m (%.3f%% of L), worst %.4g m\n",
              std::hypot((w.centreOfMass(hs.back()) - c0.back()).x(),
                         (w.centreOfMass(hs.back()) - c0.back()).z()),
              100 *
                  std::hypot((w.centreOfMass(hs.back()) - c0.back()).x(),
                             (w.centreOfMass(hs.back()) - c0.back()).z()) /
                  L,
              worst);
  return 0;
}

// A body dropped from height H onto the floor: rebound ratio (apex height / drop height).
int drop() {
  const double L = num("L", 0.4), H = num("H", 1.0), T = num("T", 3);
  World w(settingsFromOptions());
  w.addCollider(floorCollider());
  const Shape s = shapeOf(str("kind", "cube"), L);
  const Mat3 R = rotXYZ(num("rx", 0), num("ry", 0), num("rz", 0));
  const double yRest = -minY(s, R);
  BodyDef d = makeBody(s, Vec3(0, yRest + H, 0), R, str("mode", "rigid"), num("alpha", 1),
                       num("beta", 0.3), num("damping", 0), num("mass", 1));
  BodyHandle b = w.addBody(d);
  const double c0 = w.centreOfMass(b).y();
  const int steps = stepsFor(w, T);
  double impactSpeed = 0, apex = -1e30;
  bool hit = false, rising = false;
  double prevVy = 0;
  for (int k = 1; k <= steps; ++k) {
    w.step();
    const double y = w.centreOfMass(b).y() - (c0 - H);
    const double vy = w.linearMomentum(b).y() / w.mass(b);
    if (!hit && vy > prevVy + 0.1) {
      hit = true;
      impactSpeed = -prevVy;
    }
    if (hit && vy > 0.02) rising = true;
    if (rising) apex = std::max(apex, y);
    prevVy = vy;
    if (num("show", 0) > 0 && k % int(num("show", 1)) == 0)
      std::printf("  t %.3f y %.4f vy %.3f maxSpeed %.3f size %.4f\n", w.time(), y, vy, maxSpeed(w),
                  rmsSize(w, b));
    if (rising && vy < -0.05) break;  // falling again
  }
  std::printf("impact speed %.3f m/s, apex after impact %.4f m, rebound ratio %.4f\n", impactSpeed,
              rising ? apex : 0.0, rising ? apex / H : 0.0);
  return 0;
}

// Rigid α = 1 body hitting the floor (or a second body): worst pairwise distance error.
int impact() {
  const double L = num("L", 0.4), T = num("T", 2);
  World w(settingsFromOptions());
  w.addCollider(floorCollider());
  const Shape s = shapeOf(str("kind", "cube"), L);
  const Mat3 R = rotXYZ(num("rx", 20), num("ry", 30), num("rz", 10));
  BodyDef d = makeBody(s, Vec3(0, -minY(s, R) + num("H", 0.5), 0), R, "rigid", 1, 0, 0, 1);
  d.velocity = Vec3(num("vx", 1), -num("v0", 3), 0);
  BodyHandle b = w.addBody(d);
  if (num("two", 0) > 0) {
    BodyDef e = makeBody(s, Vec3(0.3 * L, -minY(s, Mat3::Identity()), 0), Mat3::Identity(), "rigid",
                         1, 0, 0, 1);
    w.addBody(e);
  }
  const Eigen::MatrixX3d rest = w.positions(b).cast<double>();
  if (num("w0", 0) != 0) {  // spin about z through the centre
    Eigen::MatrixX3d v(rest.rows(), 3);
    const Vec3 c = w.centreOfMass(b);
    for (int i = 0; i < rest.rows(); ++i)
      v.row(i) = (Vec3(num("vx", 1), -num("v0", 3), 0) +
                  Vec3(0, 0, num("w0", 0)).cross(Vec3(rest.row(i).transpose()) - c))
                     .transpose();
    w.setState(b, rest, v);
  }
  const int steps = stepsFor(w, T);
  double worst = 0;
  for (int k = 1; k <= steps; ++k) {
    w.step();
    worst = std::max(worst, pairError(w, b, rest));
  }
  std::printf("worst pairwise distance error %.4g %%\n", 100 * worst);
  return 0;
}

// Two bodies in free space hitting each other: momentum change per collision.
int momentumTest() {
  const double L = num("L", 0.5);
  WorldSettings ws = settingsFromOptions();
  ws.gravity = Vec3::Zero();
  World w(ws);
  const Shape s1 = shapeOf(str("kind", "bunny"), L), s2 = shapeOf(str("kind2", "suzanne"), L);
  BodyDef a = makeBody(s1, Vec3(-0.6 * L, 0.1 * L, 0), rotXYZ(10, 20, 30), str("mode", "linear"),
                       num("alpha", 0.6), 0.3, 0, 1.0);
  a.velocity = Vec3(num("v0", 3), 0.2, 0.1);
  BodyDef b = makeBody(s2, Vec3(0.6 * L, 0, 0.05 * L), rotXYZ(-5, 40, 0), str("mode2", "rigid"),
                       num("alpha2", 1), 0.3, 0, 2.0);
  b.velocity = Vec3(-num("v0", 3), 0, 0);
  BodyHandle ha = w.addBody(a), hb = w.addBody(b);
  const Vec3 p0 = momentum(w);
  const double mv0 = sumMV(w);
  const Vec3 L0 = w.angularMomentum(ha) + w.angularMomentum(hb);
  const int steps = int(num("steps", 120));
  double worst = 0;
  int contactSteps = 0;
  for (int k = 1; k <= steps; ++k) {
    w.step();
    worst = std::max(worst, (momentum(w) - p0).norm() / mv0);
    contactSteps += w.lastContactCount() > 0;
  }
  const Vec3 L1 = w.angularMomentum(ha) + w.angularMomentum(hb);
  std::printf(
      "|ΔP|/Σm|v|: end %.3g, worst %.3g; |ΔL|/|L0| %.3g; steps with contact %d; |P_a| change "
      "%.3g\n",
      (momentum(w) - p0).norm() / mv0, worst, (L1 - L0).norm() / std::max(L0.norm(), 1e-12),
      contactSteps, (w.linearMomentum(ha) - Vec3(num("v0", 3), 0.2, 0.1)).norm());
  return 0;
}

// Two bodies starting overlapped by `depth` × L: time to separate, peak speed.
int overlap() {
  const double L = num("L", 0.5), depth = num("depth", 0.3), T = num("T", 2);
  World w(settingsFromOptions());
  w.addCollider(floorCollider());
  const Shape s = shapeOf(str("kind", "cube"), L);
  const double y = -minY(s, Mat3::Identity()) + 0.001;
  BodyDef a = makeBody(s, Vec3(-0.5 * L + 0.5 * depth * L, y, 0), Mat3::Identity(),
                       str("mode", "rigid"), num("alpha", 1), 0.3, num("damping", 0), 1);
  BodyDef b = makeBody(s, Vec3(0.5 * L - 0.5 * depth * L, y, 0), Mat3::Identity(),
                       str("mode", "rigid"), num("alpha", 1), 0.3, num("damping", 0), 1);
  std::vector<Shape> shapes{s, s};
  const BodyHandle ha = w.addBody(a), hb = w.addBody(b);
  const int steps = stepsFor(w, T);
  double peak = 0, sepTime = -1;
  for (int k = 1; k <= steps; ++k) {
    w.step();
    peak = std::max(peak, maxSpeed(w));
    if (num("trace", 0) > 0)
      std::printf("%.4f max %.3f a v_c %.3f w %.3f | b v_c %.3f w %.3f\n", w.time(), maxSpeed(w),
                  (w.linearMomentum(ha) / w.mass(ha)).norm(),
                  w.angularMomentum(ha, w.centreOfMass(ha)).norm(),
                  (w.linearMomentum(hb) / w.mass(hb)).norm(),
                  w.angularMomentum(hb, w.centreOfMass(hb)).norm());
    if (sepTime < 0 && deepestPenetration(w, shapes, nullptr) < 0.01) sepTime = w.time();
  }
  std::printf(
      "separated (depth < 1%% spacing) at %.3f s, peak speed %.3g m/s, final max speed %.3g, "
      "deepest %.3g spacings, centres %.3g L apart\n",
      sepTime, peak, maxSpeed(w), deepestPenetration(w, shapes, nullptr),
      (w.centreOfMass(ha) - w.centreOfMass(hb)).norm() / L);
  return 0;
}

// A deformed body in free space (no gravity, no colliders): does shape matching keep, lose or
// gain energy by itself?
int freeBody() {
  const double L = num("L", 0.5), T = num("T", 20);
  WorldSettings ws = settingsFromOptions();
  ws.gravity = Vec3::Zero();
  World w(ws);
  const Shape s = shapeOf(str("kind", "suzanne"), L);
  BodyDef d = makeBody(s, Vec3::Zero(), Mat3::Identity(), str("mode", "linear"), num("alpha", 0.6),
                       num("beta", 0.3), num("damping", 0), 1.0);
  BodyHandle b = w.addBody(d);
  Eigen::MatrixX3d x = w.positions(b).cast<double>(), v = Eigen::MatrixX3d::Zero(x.rows(), 3);
  for (int i = 0; i < x.rows(); ++i) {
    x(i, 1) *= 0.8;
    x(i, 0) *= 1.1;
    v.row(i) = Vec3(0, 0, num("spin", 1)).cross(Vec3(x.row(i).transpose())).transpose();
  }
  w.setState(b, x, v);
  const int steps = stepsFor(w, T);
  const int every = std::max(1, steps / 10);
  const double size0 = rmsSize(w, b);
  for (int k = 1; k <= steps; ++k) {
    w.step();
    if (k % every == 0)
      std::printf("%6.2f %10.4g %10.4g %8.4f\n", w.time(), maxSpeed(w), kinetic(w),
                  rmsSize(w, b) / size0);
  }
  return 0;
}

// A scene file: fastest particle over time, when it last moved at 1 cm/s or more.
int sceneRun() {
  Scene sc = loadScene(str("path", std::string(SOFTBODY_ASSET_DIR) + "/scenes/default.json"));
  World& w = sc.world;
  if (num("nodamp", 0) > 0)
    for (BodyHandle b : w.bodies()) {
      BodyParams p = w.params(b);
      p.damping = 0;
      w.setParams(b, p);
    }
  WorldSettings ws = w.settings();
  applyWorldOptions(ws);
  w.setSettings(ws);
  const double T = num("T", 20);
  const int steps = stepsFor(w, T);
  double lastAwake = 0, peak = 0, peakLate = 0, lastImpact = 0, asleepAt = -1;
  double lateSteps = 0, lateMoving = 0, lateSum = 0;  // the last 10 s
  const int every = std::max(1, int(num("every", steps / 10)));
  const int n = int(w.bodies().size());
  std::vector<double> prevVy(size_t(n), 0.0);
  // A particle impact: some particle's velocity changed by more than 0.5 m/s in one step (30 m/s²
  // at 60 Hz, three times gravity: a hit, a body landing on its side after tipping over, or a
  // rocking body changing pivot; not gravity, spin or sliding).
  double lastParticleImpact = 0;
  std::vector<Eigen::MatrixX3f> prevV{size_t(n)};
  std::unique_ptr<StillnessCensus> census;
  if (num("stillness", 0) > 0) census = std::make_unique<StillnessCensus>(w);
  const double cpu0 = cpuSeconds();
  const double plasticUntil = num("plastic_until", 1e30);  // then no flow: flow or walk?
  for (int k = 1; k <= steps; ++k) {
    if (has("late_at") && std::abs(w.time() - num("late_at", 0)) < 0.5 * w.settings().timeStep) {
      // From here on, other settings: which of them the late motion depends on.
      WorldSettings late = w.settings();
#ifndef LAB_BASELINE
      if (has("late_roll")) late.rollingResistance = num("late_roll", 0.05);
#endif
      if (has("late_sub")) late.substeps = int(num("late_sub", 4));
      if (has("late_bmu")) late.contactFriction = num("late_bmu", 0.5);
      w.setSettings(late);
      if (has("late_mu")) {
        std::vector<Collider> cs = w.colliders();
        w.clearColliders();
        for (Collider c : cs) {
          c.friction = num("late_mu", 0.6);
          w.addCollider(c);
        }
      }
      if (has("late_damping") || has("late_alpha"))
        for (BodyHandle b : w.bodies()) {
          BodyParams p = w.params(b);
          if (p.mode == Mode::Rigid) continue;
          if (has("late_damping")) p.damping = num("late_damping", 0.2);
          if (has("late_alpha")) p.alpha = num("late_alpha", 0.5);
          w.setParams(b, p);
        }
    }
    if (w.time() >= plasticUntil)
      for (BodyHandle b : w.bodies()) {
        BodyParams p = w.params(b);
        // Once: setParams wakes the body, so setting it every step would keep it from sleeping.
        if (!p.plasticity.enabled() || p.plasticity.yield >= 1e6) continue;
        p.plasticity.yield = 1e6;  // no more flow; the permanent deformation stays
        w.setParams(b, p);
      }
    w.step();
    const double v = maxSpeed(w);
    peak = std::max(peak, v);
    if (w.time() > T - 5) peakLate = std::max(peakLate, v);
    if (w.time() > T - 10) {
      lateSteps += 1;
      lateMoving += v >= 0.01 ? 1 : 0;
      lateSum += v;
    }
    if (v >= 0.01) lastAwake = w.time();
    if (num("spike", 0) > 0 && w.time() > 4 && v > 0.008) {  // which particle jumps, and how
      for (BodyHandle b : w.bodies()) {
        int i = 0;
        const double bv = w.velocities(b).rowwise().norm().maxCoeff(&i);
        if (bv < 0.008) continue;
        const Eigen::RowVector3f x = w.positions(b).row(i), u = w.velocities(b).row(i);
        std::printf("spike %.4f %s particle %d v (%.4f %.4f %.4f) x (%.4f %.4f %.4f)\n", w.time(),
                    w.name(b).c_str(), i, u.x(), u.y(), u.z(), x.x(), x.y(), x.z());
      }
    }
    // An impact: some body's centre velocity changed by more than 0.5 m/s in one step.
    const auto bs = w.bodies();
    for (int i = 0; i < n; ++i) {
      const Vec3 vc = w.linearMomentum(bs[size_t(i)]) / w.mass(bs[size_t(i)]);
      if (std::abs(vc.y() - prevVy[size_t(i)]) > 0.5) lastImpact = w.time();
      prevVy[size_t(i)] = vc.y();
      const Eigen::MatrixX3f u = w.velocities(bs[size_t(i)]);
      if (prevV[size_t(i)].rows() == u.rows() &&
          (u - prevV[size_t(i)]).rowwise().norm().maxCoeff() > 0.5)
        lastParticleImpact = w.time();
      prevV[size_t(i)] = u;
    }
    if (census) {
      census->observe(w);
      if (k % every == 0) census->report(w);
    }
    const int sleeping = sleepingCount(w);
    if (sleeping == n && asleepAt < 0) asleepAt = w.time();
    if (sleeping < n) asleepAt = -1;
    if (k % every == 0) {
      std::printf("%6.2f maxSpeed %.4g KE %.4g sleeping %d", w.time(), v, kinetic(w), sleeping);
      if (num("who", 0) > 0) {  // the fastest body: name, mode, α, centre velocity and height
        size_t f = 0;
        double fv = -1;
        for (size_t i = 0; i < bs.size(); ++i) {
          const double bv = w.velocities(bs[i]).rowwise().norm().maxCoeff();
          if (bv > fv) {
            fv = bv;
            f = i;
          }
        }
        const Vec3 vc = w.linearMomentum(bs[f]) / w.mass(bs[f]);
        const Vec3 c = w.centreOfMass(bs[f]);
        std::printf("  fastest %s (%s α %.2f) v_c (%.3f %.3f %.3f) c (%.3f %.3f %.3f)",
                    w.name(bs[f]).c_str(), modeName(w.params(bs[f]).mode), w.params(bs[f]).alpha,
                    vc.x(), vc.y(), vc.z(), c.x(), c.y(), c.z());
      }
      std::printf("\n");
      if (num("bodies", 0) > 0 || !str("track", "").empty())  // asleep, centre, lowest, fastest
        for (BodyHandle b : bs) {
          if (!str("track", "").empty() && w.name(b).find(str("track", "")) == std::string::npos)
            continue;
          const Vec3 c = w.centreOfMass(b);
          std::printf("    %-12s %s c (%.5f %.5f %.5f) lowest %.5f fastest %.3g", w.name(b).c_str(),
                      w.isSleeping(b) ? "asleep" : "awake ", c.x(), c.y(), c.z(),
                      w.positions(b).col(1).minCoeff(),
                      w.velocities(b).rowwise().norm().maxCoeff());
          if (num("energy", 0) > 0) {  // kinetic energy split: centre, rigid spin, the rest
            const Eigen::VectorXf m = w.masses(b);
            const auto x = w.positions(b);
            const auto u = w.velocities(b);
            const double M = w.mass(b);
            const Vec3 vc = w.linearMomentum(b) / M;
            Mat3 I = Mat3::Zero();
            double ke = 0;
            for (int i = 0; i < int(m.size()); ++i) {
              const Vec3 r = x.row(i).cast<double>().transpose() - c;
              I += m[i] * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
              ke += 0.5 * m[i] * u.row(i).cast<double>().squaredNorm();
            }
            const Vec3 L = w.angularMomentum(b, c);
            const double lin = 0.5 * M * vc.squaredNorm();
            const double rot = 0.5 * L.dot(I.ldlt().solve(L));
            std::printf(" KE lin %.3g rot %.3g def %.3g; E %.5g", lin, rot, ke - lin - rot,
                        ke + M * 9.81 * c.y());
          }
          std::printf("\n");
        }
    }
  }
  std::printf(
      "peak %.3g m/s; fastest in the last 5 s %.3g m/s; last time >= 1 cm/s: %.2f s; last impact "
      "%.2f s (a particle's: %.2f s); all asleep from %.2f s (of %.0f); CPU %.2f s; last 10 s: "
      "mean fastest %.3g m/s, %.0f steps >= 1 cm/s; state hash %016llx\n",
      peak, peakLate, lastAwake, lastImpact, lastParticleImpact, asleepAt, T, cpuSeconds() - cpu0,
      lateSum / std::max(1.0, lateSteps), lateMoving, (unsigned long long)w.stateHash());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: contact_lab softrigid|pile|rest|stack|drop|impact|momentum|overlap|"
                 "free|scene [key=value...]\n");
    return 2;
  }
  for (int i = 2; i < argc; ++i) {
    std::string a = argv[i];
    const size_t eq = a.find('=');
    if (eq != std::string::npos) opt[a.substr(0, eq)] = a.substr(eq + 1);
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  if (has("threads")) setThreadCount(int(num("threads", 1)));
  const std::string sc = argv[1];
  if (sc == "softrigid") return softRigid();
  if (sc == "pile") return pile();
  if (sc == "rest") return rest();
  if (sc == "stack") return stack();
  if (sc == "drop") return drop();
  if (sc == "impact") return impact();
  if (sc == "momentum") return momentumTest();
  if (sc == "overlap") return overlap();
  if (sc == "free") return freeBody();
  if (sc == "scene") return sceneRun();
  std::fprintf(stderr, "unknown scenario %s\n", sc.c_str());
  return 2;
}
