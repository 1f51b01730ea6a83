// Constrained quadric edge-collapse decimation: see auto_cage_decimate.h.
#include "sim/cage/auto_cage_decimate.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <queue>
#include <utility>

#include <Eigen/Cholesky>

namespace sb::cage::detail {

namespace {

// Smallest accepted quality 4√3·area / Σ edge² of a new triangle (1 = equilateral): slivers make
// mean value coordinates ill-conditioned and the intersection tests fragile.
constexpr double kMinQuality = 0.03;
// Weight of the edge-length term added to a candidate's quadric error when it is queued: cost +
// kEdgeTie·|a − b|⁴ (voxel frame; the quadric is area-weighted, so both are lengths⁴). Where the
// planes decide (curved parts) it changes nothing: for an edge of length L on a surface of radius
// R voxels the quadric is ~L⁶/(64R²), which outweighs the term once L > 0.08·R. On flat parts
// every collapse costs ~0, and without the term the ties went to the lowest vertex index, so one
// vertex swallowed its whole face: fans of up to 186 triangles whose checks grow with the square
// of their size, and slivers at the kMinQuality floor (a 120k-triangle box: 2.9 s of decimation
// and a median triangle quality of 0.07; with the term 0.3 s and 0.87, same Hausdorff).
constexpr double kEdgeTie = 1e-4;

// Squared distance to a set of planes, area-weighted: x·A·x + 2·b·x + c.
struct Quadric {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Vec b = Vec::Zero();
  double c = 0.0;
  Quadric& operator+=(const Quadric& o) {
    A += o.A;
    b += o.b;
    c += o.c;
    return *this;
  }
  double operator()(const Vec& x) const { return x.dot(A * x) + 2.0 * b.dot(x) + c; }
};

// Cage triangles by the cells (kCell voxels wide) their bounding boxes overlap; positions outside
// the grid fall in its border cells (clamped alike when inserting and querying).
class TriangleGrid {
 public:
  static constexpr double kCell = 4.0;
  TriangleGrid(const Vec& hi, std::size_t triangleCount)
      : ranges_(triangleCount), stamp_(triangleCount, 0) {
    for (int d = 0; d < 3; ++d) n_[d] = std::max(1, static_cast<int>(std::ceil(hi[d] / kCell)) + 1);
    cells_.resize(std::size_t(n_[0]) * n_[1] * n_[2]);
  }
  void insert(int t, const Vec& lo, const Vec& hi) {
    const std::array<int, 6> r = range(lo, hi);
    ranges_[static_cast<std::size_t>(t)] = r;
    forCells(r, [&](std::vector<int>& cell) { cell.push_back(t); });
  }
  void remove(int t) {
    forCells(ranges_[static_cast<std::size_t>(t)],
             [&](std::vector<int>& cell) { cell.erase(std::find(cell.begin(), cell.end(), t)); });
  }
  // Calls f(t) once for every triangle registered in a cell that [lo, hi] overlaps.
  template <typename F>
  void query(const Vec& lo, const Vec& hi, const F& f) {
    ++current_;
    forCells(range(lo, hi), [&](std::vector<int>& cell) {
      for (const int t : cell) {
        unsigned& s = stamp_[static_cast<std::size_t>(t)];
        if (s == current_) continue;
        s = current_;
        f(t);
      }
    });
  }

 private:
  std::array<int, 6> range(const Vec& lo, const Vec& hi) const {
    std::array<int, 6> r{};
    for (int d = 0; d < 3; ++d) {
      r[static_cast<std::size_t>(d)] =
          std::clamp(static_cast<int>(std::floor(lo[d] / kCell)), 0, n_[d] - 1);
      r[static_cast<std::size_t>(d + 3)] =
          std::clamp(static_cast<int>(std::floor(hi[d] / kCell)), 0, n_[d] - 1);
    }
    return r;
  }
  template <typename F>
  void forCells(const std::array<int, 6>& r, const F& f) {
    for (int k = r[2]; k <= r[5]; ++k)
      for (int j = r[1]; j <= r[4]; ++j)
        for (int i = r[0]; i <= r[3]; ++i)
          f(cells_[std::size_t(i) +
                   std::size_t(n_[0]) * (std::size_t(j) + std::size_t(n_[1]) * std::size_t(k))]);
  }
  std::array<int, 3> n_{};
  std::vector<std::vector<int>> cells_;
  std::vector<std::array<int, 6>> ranges_;
  std::vector<unsigned> stamp_;
  unsigned current_ = 0;
};

struct Candidate {
  double cost;
  int a, b;
  unsigned versionA, versionB;
  bool operator>(const Candidate& o) const {
    if (cost != o.cost) return cost > o.cost;
    if (a != o.a) return a > o.a;
    return b > o.b;
  }
};

bool boxesOverlap(const Vec& lo1, const Vec& hi1, const Vec& lo2, const Vec& hi2) {
  return (lo1.array() <= hi2.array()).all() && (lo2.array() <= hi1.array()).all();
}

class Decimator {
 public:
  Decimator(mesh::TriangleMesh& cage, const GuardSet& guards, double clearance, double maxDeviation)
      : cage_(cage),
        guards_(guards),
        clearance_(clearance),
        maxDeviation_(maxDeviation),
        alive_(cage.triangles.size(), 1),
        vertexTriangles_(cage.vertices.size()),
        vertexAlive_(cage.vertices.size(), 1),
        version_(cage.vertices.size(), 0),
        quadrics_(cage.vertices.size()),
        aliveVertices_(static_cast<int>(cage.vertices.size())),
        grid_(maxCorner(cage), cage.triangles.size()),
        fanMark_(cage.triangles.size(), 0) {
    for (std::size_t t = 0; t < cage.triangles.size(); ++t) {
      const Tri& tri = cage.triangles[t];
      const Vec n = (corner(tri, 1) - corner(tri, 0)).cross(corner(tri, 2) - corner(tri, 0));
      const double len = n.norm();
      Quadric q;
      if (len > 0) {
        const Vec u = n / len;
        const double d = -u.dot(corner(tri, 0)), w = 0.5 * len;
        q.A = w * u * u.transpose();
        q.b = w * d * u;
        q.c = w * d * d;
      }
      for (const int v : tri) {
        vertexTriangles_[static_cast<std::size_t>(v)].push_back(static_cast<int>(t));
        quadrics_[static_cast<std::size_t>(v)] += q;
      }
      insertInGrid(static_cast<int>(t));
    }
  }

  void run(int budget) {
    for (;;) {
      for (std::size_t t = 0; t < cage_.triangles.size(); ++t) {
        if (!alive_[t]) continue;
        for (int k = 0; k < 3; ++k) {
          const int a = cage_.triangles[t][static_cast<std::size_t>(k)],
                    b = cage_.triangles[t][static_cast<std::size_t>((k + 1) % 3)];
          if (a < b) push(a, b);
        }
      }
      bool progress = false;
      while (!heap_.empty() && aliveVertices_ > budget) {
        const Candidate c = heap_.top();
        heap_.pop();
        if (!vertexAlive_[static_cast<std::size_t>(c.a)] ||
            !vertexAlive_[static_cast<std::size_t>(c.b)] ||
            version_[static_cast<std::size_t>(c.a)] != c.versionA ||
            version_[static_cast<std::size_t>(c.b)] != c.versionB)
          continue;
        if (tryCollapse(c.a, c.b)) progress = true;
      }
      heap_ = {};
      if (aliveVertices_ <= budget) break;
      // Refused collapses are retried once their neighbourhood has changed: another pass; when
      // a pass made none, the deviation limit is relaxed (after 12 relaxations, ×130, it no
      // longer binds).
      if (!progress) {
        if (relaxations_ == kMaxRelaxations) break;
        ++relaxations_;
        maxDeviation_ = relaxations_ == kMaxRelaxations ? std::numeric_limits<double>::infinity()
                                                        : 1.5 * maxDeviation_;
      }
    }
    compact();
  }

 private:
  static Vec maxCorner(const mesh::TriangleMesh& m) {
    Vec hi = Vec::Zero();
    for (const Vec& v : m.vertices) hi = hi.cwiseMax(v);
    return hi;
  }
  const Vec& corner(const Tri& t, int k) const {
    return cage_.vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])];
  }
  std::array<Vec, 3> corners(int t) const {
    const Tri& tri = cage_.triangles[static_cast<std::size_t>(t)];
    return {corner(tri, 0), corner(tri, 1), corner(tri, 2)};
  }
  void insertInGrid(int t) {
    const std::array<Vec, 3> c = corners(t);
    grid_.insert(t, c[0].cwiseMin(c[1]).cwiseMin(c[2]), c[0].cwiseMax(c[1]).cwiseMax(c[2]));
  }
  std::vector<int> neighbours(int v) const {
    std::vector<int> out;
    for (const int t : vertexTriangles_[static_cast<std::size_t>(v)])
      for (const int u : cage_.triangles[static_cast<std::size_t>(t)])
        if (u != v) out.push_back(u);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  // Target positions of collapsing edge (a, b), cheapest first: the quadric's minimiser
  // (regularised toward the midpoint so flat and creased neighbourhoods have one), the midpoint
  // and both endpoints. A minimiser farther than the edge's length from the midpoint is dropped
  // (cost +∞): nearly dependent planes put it far out, and enclosure alone does not stop the
  // cage from bulging there (measured: 6.96 % Hausdorff on two overlapping boxes with it).
  std::array<std::pair<double, Vec>, 4> targets(int a, int b) const {
    Quadric q = quadrics_[static_cast<std::size_t>(a)];
    q += quadrics_[static_cast<std::size_t>(b)];
    const Vec &pa = cage_.vertices[static_cast<std::size_t>(a)],
              &pb = cage_.vertices[static_cast<std::size_t>(b)];
    const Vec mid = 0.5 * (pa + pb);
    const double lambda = 1e-3 * q.A.trace() + 1e-12;
    const Vec opt = (q.A + lambda * Eigen::Matrix3d::Identity()).ldlt().solve(lambda * mid - q.b);
    const double optCost =
        (opt - mid).norm() <= (pa - pb).norm() ? q(opt) : std::numeric_limits<double>::infinity();
    std::array<std::pair<double, Vec>, 4> out{
        {{optCost, opt}, {q(mid), mid}, {q(pa), pa}, {q(pb), pb}}};
    std::stable_sort(out.begin(), out.end(),
                     [](const auto& x, const auto& y) { return x.first < y.first; });
    return out;
  }

  // Queues edge (a, b) by its cheapest target's quadric error plus the edge-length tie-break.
  void push(int a, int b) {
    if (a > b) std::swap(a, b);
    const double length2 =
        (cage_.vertices[static_cast<std::size_t>(a)] - cage_.vertices[static_cast<std::size_t>(b)])
            .squaredNorm();
    heap_.push({targets(a, b)[0].first + kEdgeTie * length2 * length2, a, b,
                version_[static_cast<std::size_t>(a)], version_[static_cast<std::size_t>(b)]});
  }

  bool tryCollapse(int a, int b) {
    if (aliveVertices_ <= 4) return false;
    fan_.clear();
    for (const int v : {a, b})
      for (const int t : vertexTriangles_[static_cast<std::size_t>(v)]) fan_.push_back(t);
    std::sort(fan_.begin(), fan_.end());
    fan_.erase(std::unique(fan_.begin(), fan_.end()), fan_.end());
    std::vector<int> opposite;
    removed_.clear();
    for (const int t : fan_) {
      const Tri& tri = cage_.triangles[static_cast<std::size_t>(t)];
      if (std::find(tri.begin(), tri.end(), a) == tri.end() ||
          std::find(tri.begin(), tri.end(), b) == tri.end())
        continue;
      removed_.push_back(t);
      for (const int u : tri)
        if (u != a && u != b) opposite.push_back(u);
    }
    if (removed_.size() != 2) return false;
    // Link condition: a and b have exactly the two opposite corners as common neighbours.
    const std::vector<int> na = neighbours(a), nb = neighbours(b);
    std::vector<int> common;
    std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
    std::sort(opposite.begin(), opposite.end());
    if (common != opposite) return false;
    if (na.size() + nb.size() - 4 < 3) return false;  // the merged vertex needs 3 neighbours
    ++fanStamp_;
    for (const int t : fan_) fanMark_[static_cast<std::size_t>(t)] = fanStamp_;
    for (const auto& target : targets(a, b))
      if (target.first < std::numeric_limits<double>::infinity() && allowed(a, b, target.second)) {
        collapse(a, b, target.second);
        return true;
      }
    return false;
  }

  // The winding-number change at x: (Σ solid angles of the new fan − Σ of the old) / 4π.
  double windingChange(const Vec& x) const {
    double s = 0.0;
    for (std::size_t i = 0; i < newFan_.size(); ++i) {
      s += solidAngle(x, newFan_[i][0], newFan_[i][1], newFan_[i][2]);
      s -= solidAngle(x, oldFan_[i][0], oldFan_[i][1], oldFan_[i][2]);
    }
    for (const int t : removed_) {
      const std::array<Vec, 3> c = corners(t);
      s -= solidAngle(x, c[0], c[1], c[2]);
    }
    return s / (4.0 * 3.14159265358979323846);
  }

  bool allowed(int a, int b, const Vec& p) {
    newFan_.clear();
    oldFan_.clear();
    newIds_.clear();
    Vec lo = p, hi = p;
    for (const int t : fan_) {
      if (std::find(removed_.begin(), removed_.end(), t) != removed_.end()) continue;
      const Tri& tri = cage_.triangles[static_cast<std::size_t>(t)];
      std::array<Vec, 3> o = corners(t), n = o;
      Tri ids = tri;
      for (int k = 0; k < 3; ++k)
        if (tri[static_cast<std::size_t>(k)] == a || tri[static_cast<std::size_t>(k)] == b) {
          n[static_cast<std::size_t>(k)] = p;
          ids[static_cast<std::size_t>(k)] = a;  // no triangle outside the fan has a corner a
        }
      const Vec n0 = (o[1] - o[0]).cross(o[2] - o[0]), n1 = (n[1] - n[0]).cross(n[2] - n[0]);
      if (!(n1.dot(n0) > 0.0)) return false;  // flipped or degenerate
      const double edges =
          (n[1] - n[0]).squaredNorm() + (n[2] - n[1]).squaredNorm() + (n[0] - n[2]).squaredNorm();
      if (2.0 * std::sqrt(3.0) * n1.norm() < kMinQuality * edges) return false;
      for (const Vec& c : n) {
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
      }
      newFan_.push_back(n);
      oldFan_.push_back(o);
      newIds_.push_back(ids);
    }
    // (e) Tightness: samples on every new triangle (at most maxDeviation apart, up to 8 per
    // edge) lie within maxDeviation of a guard point, so no face spans a concavity or a gap.
    if (maxDeviation_ < std::numeric_limits<double>::infinity())
      for (const auto& n : newFan_) {
        const double longest =
            std::max({(n[1] - n[0]).norm(), (n[2] - n[1]).norm(), (n[0] - n[2]).norm()});
        const int k = std::clamp(static_cast<int>(std::ceil(longest / maxDeviation_)), 1, 8);
        for (int i = 0; i <= k; ++i)
          for (int j = 0; i + j <= k; ++j)
            if (!nearGuard((1.0 - double(i + j) / k) * n[0] + double(i) / k * n[1] +
                           double(j) / k * n[2]))
              return false;
      }
    // (b) No intersection with the rest of the cage, nor within the new fan.
    bool clash = false;
    grid_.query(lo, hi, [&](int t) {
      if (clash || fanMark_[static_cast<std::size_t>(t)] == fanStamp_) return;
      const std::array<Vec, 3> c = corners(t);
      const Vec tlo = c[0].cwiseMin(c[1]).cwiseMin(c[2]), thi = c[0].cwiseMax(c[1]).cwiseMax(c[2]);
      for (std::size_t i = 0; i < newFan_.size() && !clash; ++i) {
        const Vec flo = newFan_[i][0].cwiseMin(newFan_[i][1]).cwiseMin(newFan_[i][2]),
                  fhi = newFan_[i][0].cwiseMax(newFan_[i][1]).cwiseMax(newFan_[i][2]);
        if (boxesOverlap(flo, fhi, tlo, thi) &&
            trianglesIntersect(newFan_[i], newIds_[i], c,
                               cage_.triangles[static_cast<std::size_t>(t)]))
          clash = true;
      }
    });
    if (clash) return false;
    for (std::size_t i = 0; i < newFan_.size(); ++i)
      for (std::size_t j = i + 1; j < newFan_.size(); ++j)
        if (trianglesIntersect(newFan_[i], newIds_[i], newFan_[j], newIds_[j])) return false;
    // (a) Enclosure. Old fan − new fan is the boundary of the tetrahedra (old triangle, p), so
    // a point's winding number can change only inside one of them: guard points outside all of
    // their boxes (grown by the clearance, which also covers the distance to the new fan) are
    // skipped; the others are tested exactly.
    swept_.clear();
    const Vec margin = Vec::Constant(clearance_);
    const auto addSwept = [&](const std::array<Vec, 3>& o) {
      swept_.push_back({o[0].cwiseMin(o[1]).cwiseMin(o[2]).cwiseMin(p) - margin,
                        o[0].cwiseMax(o[1]).cwiseMax(o[2]).cwiseMax(p) + margin});
      lo = lo.cwiseMin(swept_.back().first);
      hi = hi.cwiseMax(swept_.back().second);
    };
    for (const auto& o : oldFan_) addSwept(o);
    for (const int t : removed_) addSwept(corners(t));
    const auto inSwept = [&](const Vec& blo, const Vec& bhi) {
      for (const auto& box : swept_)
        if (boxesOverlap(blo, bhi, box.first, box.second)) return true;
      return false;
    };
    guards_.bucketsIn(lo, hi, buckets_);
    for (const int id : buckets_) {
      const GuardSet::Bucket& bucket = guards_.buckets[static_cast<std::size_t>(id)];
      if (!inSwept(bucket.lo, bucket.hi)) continue;
      double near = std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < newFan_.size(); ++i)
        near = std::min(
            {near,
             pointTriangleDistance(bucket.centre, newFan_[i][0], newFan_[i][1], newFan_[i][2]),
             pointTriangleDistance(bucket.centre, oldFan_[i][0], oldFan_[i][1], oldFan_[i][2])});
      for (const int t : removed_) {
        const std::array<Vec, 3> c = corners(t);
        near = std::min(near, pointTriangleDistance(bucket.centre, c[0], c[1], c[2]));
      }
      if (near > bucket.radius + clearance_) {
        // No moved surface reaches the bucket's ball: one winding number for all its points.
        if (std::abs(windingChange(bucket.centre)) > 0.5) return false;
        continue;
      }
      // A ball around an evaluated point q that reaches neither fan holds points with q's
      // (zero) winding change; those at least clearance inside it from its rim need no test.
      Vec q = Vec::Zero();
      double radius = 0.0;
      for (int g = bucket.begin; g < bucket.end; ++g) {
        const Vec& x = guards_.points[static_cast<std::size_t>(g)];
        if (!inSwept(x, x)) continue;
        if ((x - q).norm() + clearance_ <= radius) continue;
        double toNew = std::numeric_limits<double>::infinity(), toOld = toNew;
        for (std::size_t i = 0; i < newFan_.size(); ++i) {
          toNew = std::min(toNew,
                           pointTriangleDistance(x, newFan_[i][0], newFan_[i][1], newFan_[i][2]));
          toOld = std::min(toOld,
                           pointTriangleDistance(x, oldFan_[i][0], oldFan_[i][1], oldFan_[i][2]));
        }
        if (toNew < clearance_) return false;
        for (const int t : removed_) {
          const std::array<Vec, 3> c = corners(t);
          toOld = std::min(toOld, pointTriangleDistance(x, c[0], c[1], c[2]));
        }
        if (std::abs(windingChange(x)) > 0.5) return false;
        q = x;
        radius = std::min(toNew, toOld);
      }
    }
    return true;
  }

  // Some guard point lies within maxDeviation of x.
  bool nearGuard(const Vec& x) {
    const Vec r = Vec::Constant(maxDeviation_);
    guards_.bucketsIn(x - r, x + r, nearBuckets_);
    const double limit = maxDeviation_ * maxDeviation_;
    for (const int id : nearBuckets_) {
      const GuardSet::Bucket& bucket = guards_.buckets[static_cast<std::size_t>(id)];
      if ((x - x.cwiseMax(bucket.lo).cwiseMin(bucket.hi)).squaredNorm() > limit) continue;
      for (int g = bucket.begin; g < bucket.end; ++g)
        if ((guards_.points[static_cast<std::size_t>(g)] - x).squaredNorm() <= limit) return true;
    }
    return false;
  }

  void collapse(int a, int b, const Vec& p) {
    for (const int t : fan_) grid_.remove(t);
    for (const int t : removed_) {
      alive_[static_cast<std::size_t>(t)] = 0;
      for (const int u : cage_.triangles[static_cast<std::size_t>(t)]) {
        if (u == a || u == b) continue;
        auto& list = vertexTriangles_[static_cast<std::size_t>(u)];
        list.erase(std::find(list.begin(), list.end(), t));
      }
    }
    std::vector<int>& around = vertexTriangles_[static_cast<std::size_t>(a)];
    around.clear();
    for (const int t : fan_) {
      if (!alive_[static_cast<std::size_t>(t)]) continue;
      for (int& u : cage_.triangles[static_cast<std::size_t>(t)])
        if (u == b) u = a;
      around.push_back(t);
    }
    vertexTriangles_[static_cast<std::size_t>(b)].clear();
    vertexAlive_[static_cast<std::size_t>(b)] = 0;
    --aliveVertices_;
    cage_.vertices[static_cast<std::size_t>(a)] = p;
    quadrics_[static_cast<std::size_t>(a)] += quadrics_[static_cast<std::size_t>(b)];
    ++version_[static_cast<std::size_t>(a)];
    ++version_[static_cast<std::size_t>(b)];
    for (const int t : around) insertInGrid(t);
    for (const int n : neighbours(a)) push(a, n);
  }

  void compact() {
    std::vector<int> index(cage_.vertices.size(), -1);
    std::vector<Vec> vertices;
    for (std::size_t v = 0; v < cage_.vertices.size(); ++v)
      if (vertexAlive_[v]) {
        index[v] = static_cast<int>(vertices.size());
        vertices.push_back(cage_.vertices[v]);
      }
    std::vector<Tri> triangles;
    for (std::size_t t = 0; t < cage_.triangles.size(); ++t)
      if (alive_[t]) {
        Tri tri = cage_.triangles[t];
        for (int& u : tri) u = index[static_cast<std::size_t>(u)];
        triangles.push_back(tri);
      }
    cage_.vertices = std::move(vertices);
    cage_.triangles = std::move(triangles);
  }

  mesh::TriangleMesh& cage_;
  const GuardSet& guards_;
  const double clearance_;
  static constexpr int kMaxRelaxations = 12;
  double maxDeviation_;
  int relaxations_ = 0;
  std::vector<std::uint8_t> alive_;
  std::vector<std::vector<int>> vertexTriangles_;
  std::vector<std::uint8_t> vertexAlive_;
  std::vector<unsigned> version_;
  std::vector<Quadric> quadrics_;
  int aliveVertices_;
  TriangleGrid grid_;
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> heap_;
  // Scratch of the collapse being tried.
  std::vector<int> fan_, removed_, buckets_, nearBuckets_;
  std::vector<unsigned> fanMark_;
  unsigned fanStamp_ = 0;
  std::vector<std::array<Vec, 3>> newFan_, oldFan_;
  std::vector<Tri> newIds_;
  std::vector<std::pair<Vec, Vec>> swept_;  // boxes of the swept tetrahedra
};

}  // namespace

void decimateCage(mesh::TriangleMesh& cage, const GuardSet& guards, int budget, double clearance,
                  double maxDeviation) {
  Decimator(cage, guards, clearance, maxDeviation).run(budget);
}

}  // namespace sb::cage::detail
