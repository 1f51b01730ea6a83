// The --stats JSON file: timings (averages per frame), each body's centre and screen bounds, a
// pixel that hits each body, the Pause checkbox's rectangle and the camera. Tests read it; it
// is rewritten atomically (temporary file + rename) every options.statsEvery frames and at exit.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <vector>

#include <imgui.h>
#include <nlohmann/json.hpp>

#include "app/viewer_app.h"
#include "render/picking.h"
#include "sim/base/file_io.h"

namespace sb::app {

namespace {

nlohmann::json vec(const glm::vec3& v) {
  return {v.x, v.y, v.z};
}

}  // namespace

bool ViewerApp::writeStats(const std::string& path) const {
  using nlohmann::json;
  const double frames = static_cast<double>(std::max<long>(timings_.frames, 1));
  const double steps = static_cast<double>(std::max<long>(timings_.steps, 1));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  json j;
  j["frame"] = frame_;
  j["simTime"] = scene_.world.time();
  j["paused"] = paused_;
  j["panelVisible"] = !options_.hideUi && !panelHidden_;
  j["keyboardToPanel"] = ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureKeyboard;
  j["window"] = {windowWidth_, windowHeight_};
  j["fps"] = static_cast<double>(timings_.frames) / std::max(seconds, 1e-9);
  j["msPerFrame"] = {{"simulation", timings_.simSum / frames},
                     {"deform", timings_.deformSum / frames},
                     {"render", timings_.renderSum / frames},
                     {"frame", timings_.frameSum / std::max(frames - 1.0, 1.0)}};
  const StepProfile& p = timings_.phaseSum;
  json perStep = json::object();
  for (Phase phase : kPhases) perStep[phaseName(phase)] = 1e3 * p[phase] / steps;
  perStep["total"] = 1e3 * p.total() / steps;
  j["msPerStep"] = perStep;
  j["steps"] = timings_.steps;
  j["events"] = eventCount_;
  j["error"] = errorMessage_;
  j["status"] = statusMessage_;
  j["scenePath"] = scene_.path;
  j["savePath"] = savePathInput_;
  j["quitDialog"] = quitDialog_;
  j["bodyCount"] = scene_.bodies.size();
  j["binding"] = embeddingRequest_.body >= 0;
  json folded = json::array();
  for (const FoldWatch::FoldedRegion& f : folds_)
    folded.push_back(
        {{"body", f.body},
         {"folded", f.report.folded},
         {"samples", f.report.samples},
         {"minDeterminant", f.report.minDeterminant},
         {"tintedVertices", views_[static_cast<std::size_t>(f.body)].tintedVertices},
         {"tintedTriangles", views_[static_cast<std::size_t>(f.body)].tintTriangles.size() / 3}});
  j["foldCheck"] = {{"enabled", foldCheck_},
                    {"watched", foldWatch_ ? foldWatch_->watchedBodies() : 0},
                    {"error", foldError_},
                    {"folded", folded}};
  j["paramUndo"] = paramUndo_.size();
  j["plots"] = {{"samples", plots_.kinetic.count()},
                {"kinetic", plots_.kinetic.last()},
                {"linearMomentum", plots_.linearMomentum.last()},
                {"angularMomentum", plots_.angularMomentum.last()},
                {"contacts", plots_.contacts.last()},
                {"deepestContactMm", plots_.deepestContact.last()}};
  json widgets = json::object();
  for (const auto& [name, r] : widgetRects_) widgets[name] = {r[0], r[1], r[2], r[3]};
  j["widgets"] = widgets;
  j["camera"] = {{"eye", vec(camera_.eye())},    {"target", vec(camera_.target)},
                 {"distance", camera_.distance}, {"yaw", camera_.yaw},
                 {"pitch", camera_.pitch},       {"right", vec(camera_.right())},
                 {"up", vec(camera_.up())},      {"forward", vec(camera_.forward())}};
  j["drag"] = {{"active", drag_.active},
               {"body", drag_.body},
               {"nearestParticle", drag_.nearestParticle},
               {"particles", drag_.particles.size()}};

  const float w = static_cast<float>(std::max(windowWidth_, 1));
  const float h = static_cast<float>(std::max(windowHeight_, 1));
  const ViewRect view = viewRect();
  const glm::mat4 viewProjection =
      camera_.projection(view.width / std::max(view.height, 1.0f)) * camera_.view();
  auto project = [&](const glm::vec3& point, glm::vec2* pixel) {
    if (!render::OrbitCamera::projectWith(viewProjection, point, view.width, view.height, pixel))
      return false;
    *pixel += glm::vec2(view.x, view.y);
    return true;
  };
  // Screen boxes (window pixels, origin top left) of projected points. A set with a point behind
  // the eye may cover any pixel: its box is the whole window.
  struct ScreenBox {
    glm::vec2 lo{std::numeric_limits<float>::max()}, hi{-std::numeric_limits<float>::max()};
    bool everywhere = false;
    bool contains(const glm::vec2& p) const {
      return everywhere || (p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y);
    }
  };
  auto boxOf = [&](const PointsRowMajor& x) {
    ScreenBox box;
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      glm::vec2 pixel;
      if (project(glm::vec3(x(r, 0), x(r, 1), x(r, 2)), &pixel)) {
        box.lo = glm::min(box.lo, pixel);
        box.hi = glm::max(box.hi, pixel);
      } else {
        box.everywhere = true;
      }
    }
    return box;
  };
  // Each body's drawn mesh, and its cage (the particles and the cage's faces): the cage encloses
  // the drawn mesh, so a ray that meets the drawn mesh meets the cage first, no later. Cages
  // have a fraction of the triangles, so they answer "could this body be in front?".
  struct Pickable {
    PointsRowMajor cage;
    const std::int32_t* cageTriangles = nullptr;
    std::size_t cageTriangleCount = 0;
    ScreenBox meshBox, cageBox;
  };
  std::vector<Pickable> pick(views_.size());
  for (std::size_t i = 0; i < views_.size(); ++i) {
    const SceneBody& body = scene_.bodies[i];
    pick[i].meshBox = boxOf(views_[i].vertices);
    if (!body.cageTriangles.empty()) {
      pick[i].cage = scene_.world.positions(body.handle).topRows(body.cageVertexCount);
      static_assert(sizeof(body.cageTriangles[0]) == 3 * sizeof(std::int32_t));
      pick[i].cageTriangles = reinterpret_cast<const std::int32_t*>(body.cageTriangles.data());
      pick[i].cageTriangleCount = body.cageTriangles.size();
      pick[i].cageBox = boxOf(pick[i].cage);
    } else {  // no cage faces: the drawn mesh stands in
      pick[i].cage = views_[i].vertices;
      pick[i].cageTriangles = views_[i].triangles.data();
      pick[i].cageTriangleCount = views_[i].triangles.size() / 3;
      pick[i].cageBox = pick[i].meshBox;
    }
  }
  auto cageHit = [&](std::size_t o, const render::Ray& ray) {
    return render::pickTriangles(ray, pick[o].cage.data(),
                                 static_cast<std::size_t>(pick[o].cage.rows()),
                                 pick[o].cageTriangles, pick[o].cageTriangleCount);
  };
  // Whether the ray through `pixel` meets body i's drawn mesh before any other body. Only bodies
  // whose cage's screen box holds the pixel can be in front, and only if the ray meets their
  // cage nearer than i's mesh (a conservative test: a pixel it rejects may still have been
  // good; the next one is tried). A cage nearer than i's own cage is nearer than i's mesh
  // too, so most hidden pixels are rejected before the costly test against i's drawn mesh.
  auto hitsFirst = [&](std::size_t i, const glm::vec2& pixel) {
    if (!pick[i].meshBox.contains(pixel)) return false;
    const render::Ray ray = rayAtCursor(pixel.x, pixel.y);
    const render::TriangleHit ownCage = cageHit(i, ray);
    if (!ownCage.hit) return false;  // cannot meet the mesh inside
    // The cages this ray meets, with their distances: a cage nearer than i's cage is nearer
    // than i's mesh too (rejected before the costly mesh test).
    std::vector<float> others;
    for (std::size_t o = 0; o < views_.size(); ++o) {
      if (o == i || !pick[o].cageBox.contains(pixel)) continue;
      const render::TriangleHit other = cageHit(o, ray);
      if (!other.hit) continue;
      if (other.distance <= ownCage.distance) return false;
      others.push_back(other.distance);
    }
    const render::TriangleHit own = render::pickTriangles(
        ray, views_[i].vertices.data(), static_cast<std::size_t>(views_[i].vertices.rows()),
        views_[i].triangles.data(), views_[i].triangles.size() / 3);
    if (!own.hit) return false;
    return std::all_of(others.begin(), others.end(), [&](float d) { return d > own.distance; });
  };
  json bodies = json::array();
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    const BodyHandle handle = scene_.bodies[i].handle;
    const Vec3 c = scene_.world.centreOfMass(handle);
    json b;
    b["name"] = scene_.world.name(handle);
    const BodyParams& params = scene_.world.params(handle);
    b["params"] = {{"alpha", params.alpha}, {"beta", params.beta}};
    // How the render mesh follows the particles: a cage method with its options, a lattice, or
    // none (the body draws its particles).
    const SceneBody& sceneBody = scene_.bodies[i];
    const cage::EmbeddingMethod& method = sceneBody.embedding;
    json embedding = {{"method", !sceneBody.render        ? "none"
                                 : sceneBody.latticeFrame ? "lattice"
                                                          : cage::embeddingKindName(method.kind)}};
    if (sceneBody.render && !sceneBody.latticeFrame) {
      if (method.kind == cage::EmbeddingKind::Harmonic)
        embedding["resolution"] = method.harmonic.resolution;
      if (method.kind == cage::EmbeddingKind::Rbf) embedding["shape"] = method.rbf.shape;
      // The weights in use, to tell a half-switched body (none: both change together).
      embedding["boundKind"] = cage::embeddingKindName(sceneBody.render->embedding->kind());
    }
    embedding["error"] = views_[i].embeddingError;
    b["embedding"] = embedding;
    int foldedSamples = 0;
    for (const FoldWatch::FoldedRegion& f : folds_)
      if (f.body == static_cast<int>(i)) foldedSamples = f.report.folded;
    b["foldedSamples"] = foldedSamples;
    b["centre"] = {c.x(), c.y(), c.z()};
    // Where the body was placed (the mean of its start positions): lets a test see a fall that
    // ended before it first looked.
    const Eigen::RowVector3f start = scene_.world.restPositions(sceneBody.handle).colwise().mean();
    b["startCentre"] = {start.x(), start.y(), start.z()};
    const ScreenBox& box = pick[i].meshBox;
    b["screenBounds"] = {box.lo.x, box.lo.y, box.hi.x, box.hi.y};
    glm::vec2 centrePixel(-1.0f);
    project(glm::vec3(c.x(), c.y(), c.z()), &centrePixel);
    b["screenCentre"] = {centrePixel.x, centrePixel.y};
    // A pixel whose ray hits this body first (null if none was found). Tried: the projected
    // centre, then the projected particles nearest the eye first (each a quarter of the way
    // towards the centre, off the silhouette), at most kGrabCandidates pixels, so a body hidden
    // behind others costs a bounded search. Large scene (54 bodies), 1280x720: 3.7 s per write
    // (machine under load) with the ring search and every body ray-cast per pixel, 15 ms now
    // (idle machine; 4 bodies get null).
    constexpr std::size_t kGrabCandidates = 48;
    std::vector<std::pair<float, glm::vec2>> candidates;  // (distance from the eye, pixel)
    candidates.push_back({0.0f, centrePixel});
    const ConstPointsRef particles = scene_.world.positions(handle);
    const glm::vec3 eye = camera_.eye();
    for (Eigen::Index r = 0; r < particles.rows(); ++r) {
      const glm::vec3 q(particles(r, 0), particles(r, 1), particles(r, 2));
      glm::vec2 pixel;
      if (project(q, &pixel))
        candidates.push_back({glm::length(q - eye), pixel + 0.25f * (centrePixel - pixel)});
    }
    std::stable_sort(candidates.begin() + 1, candidates.end(),
                     [](const auto& u, const auto& v) { return u.first < v.first; });
    json grab = nullptr;
    std::size_t tried = 0;
    for (const auto& candidate : candidates) {
      const glm::vec2 pixel = glm::floor(candidate.second) + 0.5f;
      if (pixel.x < 0 || pixel.y < 0 || pixel.x >= w || pixel.y >= h) continue;
      if (pixel.x < view.x + 4.0f) continue;  // under the panel
      if (hitsFirst(i, pixel)) {
        grab = {static_cast<int>(pixel.x), static_cast<int>(pixel.y)};
        break;
      }
      if (++tried == kGrabCandidates) break;
    }
    b["grabPixel"] = grab;
    bodies.push_back(b);
  }
  j["bodies"] = bodies;

  try {
    writeFileAtomic(path, [&](std::ostream& out) { out << j.dump(2) << "\n"; });
    return true;
  } catch (const FileError& e) {
    std::fprintf(stderr, "softbody: cannot write the stats file: %s\n", e.what());
    return false;
  }
}

}  // namespace sb::app
