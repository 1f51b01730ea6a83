// The --stats JSON file: timings (averages per frame), each body's centre and screen bounds, a
// pixel that hits each body, the Pause checkbox's rectangle and the camera. Tests read it; it
// is rewritten atomically (temporary file + rename), on a thread of its own (StatsFileWriter),
// every options.statsEvery frames and at exit.
#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include <imgui.h>
#include <nlohmann/json.hpp>

#include "app/stats_file_writer.h"
#include "app/viewer_app.h"
#include "render/picking.h"

namespace sb::app {

namespace {

nlohmann::json vec(const glm::vec3& v) {
  return {v.x, v.y, v.z};
}

}  // namespace

bool ViewerApp::writeStats() {
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
  j["addingBodies"] = pendingBodies_.size();  // mesh bodies whose cage is being made
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
  // One pass without branches over the rows (it runs over every vertex of every drawn mesh), in
  // eight independent lanes so that the compiler can use vector instructions (the large scene's
  // 100k vertices with the cages: 0.43 -> 0.26 ms per write).
  auto boxOf = [&](const Eigen::Ref<const PointsRowMajor>& x) {
    const glm::mat4& m = viewProjection;
    constexpr Eigen::Index kLanes = 8;
    constexpr float kBig = std::numeric_limits<float>::max();
    std::array<float, kLanes> lowX, highX, lowY, highY, nearest;
    lowX.fill(kBig), lowY.fill(kBig), nearest.fill(kBig), highX.fill(-kBig), highY.fill(-kBig);
    auto add = [&](const float* q, std::size_t k) {
      const float clipX = m[0][0] * q[0] + m[1][0] * q[1] + m[2][0] * q[2] + m[3][0];
      const float clipY = m[0][1] * q[0] + m[1][1] * q[1] + m[2][1] * q[2] + m[3][1];
      const float clipW = m[0][3] * q[0] + m[1][3] * q[1] + m[2][3] * q[2] + m[3][3];
      nearest[k] = std::min(nearest[k], clipW);
      const float invW = 1.0f / clipW;
      const float ndcX = clipX * invW, ndcY = clipY * invW;
      lowX[k] = std::min(lowX[k], ndcX);
      highX[k] = std::max(highX[k], ndcX);
      lowY[k] = std::min(lowY[k], ndcY);
      highY[k] = std::max(highY[k], ndcY);
    };
    const Eigen::Index rows = x.rows(), whole = rows - rows % kLanes;
    const float* q = x.data();
    for (Eigen::Index r = 0; r < whole; r += kLanes, q += 3 * kLanes)
      for (std::size_t k = 0; k < kLanes; ++k) add(q + 3 * k, k);
    for (Eigen::Index r = whole; r < rows; ++r, q += 3) add(q, 0);
    const float loX = *std::min_element(lowX.begin(), lowX.end());
    const float hiX = *std::max_element(highX.begin(), highX.end());
    const float loY = *std::min_element(lowY.begin(), lowY.end());
    const float hiY = *std::max_element(highY.begin(), highY.end());
    const float nearestW = *std::min_element(nearest.begin(), nearest.end());
    ScreenBox box;
    if (x.rows() == 0) return box;
    // The same pixels as projectWith gives (y down), so the box holds every projected point.
    box.lo = glm::vec2(view.x + (loX + 1.0f) * 0.5f * view.width,
                       view.y + (1.0f - hiY) * 0.5f * view.height);
    box.hi = glm::vec2(view.x + (hiX + 1.0f) * 0.5f * view.width,
                       view.y + (1.0f - loY) * 0.5f * view.height);
    box.everywhere = !(nearestW > 1e-6f);  // a point behind the eye
    return box;
  };
  // Each body's drawn mesh, and its cage (the particles and the cage's faces): the cage encloses
  // the drawn mesh, so a ray that meets the drawn mesh meets the cage first, no later. Cages
  // have a fraction of the triangles, so they answer "could this body be in front?".
  using PointsView = Eigen::Map<const PointsRowMajor>;
  struct Pickable {
    // The cage's #C×3 points: cageRows (the World's are column-major), or the drawn mesh's.
    PointsRowMajor cageRows;
    const float* cagePoints = nullptr;
    Eigen::Index cagePointCount = 0;
    PointsView cage() const { return PointsView(cagePoints, cagePointCount, 3); }
    const std::int32_t* cageTriangles = nullptr;
    std::size_t cageTriangleCount = 0;
    ScreenBox meshBox;
    glm::vec3 centre{0.0f};  // a sphere holding the cage, to skip most ray–cage tests
    float radius = 0.0f;
    glm::vec3 low{0.0f}, high{0.0f};  // the cage's box, tighter: skips most of the rest
  };
  std::vector<Pickable> pick(views_.size());
  for (std::size_t i = 0; i < views_.size(); ++i) {
    const SceneBody& body = scene_.bodies[i];
    pick[i].meshBox = boxOf(views_[i].vertices);
    if (!body.cageTriangles.empty()) {
      pick[i].cageRows = scene_.world.positions(body.handle).topRows(body.cageVertexCount);
      pick[i].cagePoints = pick[i].cageRows.data();
      pick[i].cagePointCount = pick[i].cageRows.rows();
      static_assert(sizeof(body.cageTriangles[0]) == 3 * sizeof(std::int32_t));
      pick[i].cageTriangles = reinterpret_cast<const std::int32_t*>(body.cageTriangles.data());
      pick[i].cageTriangleCount = body.cageTriangles.size();
    } else {  // no cage faces: the drawn mesh stands in
      pick[i].cagePoints = views_[i].vertices.data();
      pick[i].cagePointCount = views_[i].vertices.rows();
      pick[i].cageTriangles = views_[i].triangles.data();
      pick[i].cageTriangleCount = views_[i].triangles.size() / 3;
    }
    const PointsView cage = pick[i].cage();
    if (cage.rows() == 0) continue;
    const Eigen::RowVector3f lo = cage.colwise().minCoeff(), hi = cage.colwise().maxCoeff();
    const Eigen::RowVector3f mid = 0.5f * (lo + hi);
    pick[i].centre = glm::vec3(mid.x(), mid.y(), mid.z());
    pick[i].low = glm::vec3(lo.x(), lo.y(), lo.z());
    pick[i].high = glm::vec3(hi.x(), hi.y(), hi.z());
    pick[i].radius = std::sqrt((cage.rowwise() - mid).rowwise().squaredNorm().maxCoeff());
  }
  // Whether the ray meets body o's cage no farther than `distance` (stops at the first such
  // triangle: a hidden candidate costs less than a full pick).
  auto cageInFront = [&](std::size_t o, const render::Ray& ray, float distance) {
    const float* x = pick[o].cagePoints;
    const std::int32_t* t = pick[o].cageTriangles;
    auto corner = [&](std::int32_t v) { return glm::vec3(x[3 * v], x[3 * v + 1], x[3 * v + 2]); };
    for (std::size_t k = 0; k < pick[o].cageTriangleCount; ++k, t += 3) {
      float along = 0, u = 0, v = 0;
      if (render::intersectRayTriangle(ray, corner(t[0]), corner(t[1]), corner(t[2]), &along, &u,
                                       &v) &&
          along <= distance)
        return true;
    }
    return false;
  };
  // Whether the viewer's pick (the nearest hit on any body's drawn mesh) through `pixel` is
  // body i, given that the ray meets i's drawn mesh at `distance`: i's nearest hit is then no
  // farther, and every other body's mesh lies inside its cage, so a body whose cage the ray meets
  // only beyond `distance` (or not at all) cannot be in front. Conservative: a pixel it rejects
  // may still have been good; the next one is tried.
  auto nothingInFront = [&](std::size_t i, const glm::vec2& pixel, const render::Ray& ray,
                            float distance) {
    for (std::size_t o = 0; o < views_.size(); ++o) {
      // A ray through a pixel outside o's drawn mesh's screen box cannot meet that mesh.
      if (o == i || !pick[o].meshBox.contains(pixel)) continue;
      // The ray enters o's sphere no earlier than s − r, s the distance along the ray to the
      // point nearest the sphere's centre: beyond `distance` (or a miss), o cannot be in front.
      const glm::vec3 toCentre = pick[o].centre - ray.origin;
      const float along = glm::dot(toCentre, ray.direction);
      const float miss2 = glm::dot(toCentre, toCentre) - along * along;
      const float r2 = pick[o].radius * pick[o].radius;
      if (miss2 > r2 || along - std::sqrt(r2 - miss2) > distance) continue;
      // The same with the box (slabs): the ray is inside all three between enter and leave. An
      // axis the ray runs along in a face's plane gives NaN, which min/max drop: that axis then
      // does not narrow the interval, which can only keep a body in, never leave one out.
      float enter = 0.0f, leave = std::numeric_limits<float>::max();
      for (int a = 0; a < 3; ++a) {
        const float inverse = 1.0f / ray.direction[a];
        const float near = (pick[o].low[a] - ray.origin[a]) * inverse;
        const float far = (pick[o].high[a] - ray.origin[a]) * inverse;
        enter = std::max(enter, std::min(near, far));
        leave = std::min(leave, std::max(near, far));
      }
      if (leave < enter || enter > distance) continue;
      if (cageInFront(o, ray, distance)) return false;
    }
    return true;
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
    // A pixel whose ray hits this body first (null if none was found). Candidates are centroids
    // of the drawn mesh's triangles: first the one that gave the last write's pixel (a frame
    // later it mostly still does), then up to kGrabSamples spread over the mesh, those facing the
    // eye first and then nearest the eye first (kGrabCandidates of them; a quarter as many, in
    // turn, for a body that had no pixel at the last write). A candidate's ray is checked against
    // its own triangle only (the pixel centre may miss a triangle smaller than a pixel) and against
    // the other bodies' cages. Large scene (54 bodies), 1280x720: 12.2 ms per write when every
    // candidate was ray-cast against the whole drawn mesh (the note of issue 16 has the figures).
    constexpr std::size_t kGrabSamples = 128, kGrabCandidates = 32;
    BodyView& drawn = views_[i];
    const std::size_t triangleCount = drawn.triangles.size() / 3;
    auto corner = [&](std::size_t t, int k) {
      const std::int32_t vertex = drawn.triangles[3 * t + static_cast<std::size_t>(k)];
      return glm::vec3(drawn.vertices(vertex, 0), drawn.vertices(vertex, 1),
                       drawn.vertices(vertex, 2));
    };
    // The pixel at triangle t's centroid if body i is what a click there picks.
    std::size_t tried = 0;
    auto grabAt = [&](std::size_t t) -> std::optional<glm::vec2> {
      const glm::vec3 a = corner(t, 0), bb = corner(t, 1), cc = corner(t, 2);
      glm::vec2 pixel;
      if (!project((a + bb + cc) / 3.0f, &pixel)) return std::nullopt;
      // The ray is checked where a press in that pixel picks: the window reports the cursor at
      // the pixel's corner (whole coordinates), not its centre. Checked at the centre, a pixel on
      // a body's outline could pass here and a press there miss the body (the pile's bunny 10,
      // half a pixel inside its top edge).
      pixel = glm::floor(pixel);
      if (pixel.x < 0 || pixel.y < 0 || pixel.x >= w || pixel.y >= h) return std::nullopt;
      if (pixel.x < view.x + 4.0f) return std::nullopt;  // under the panel
      ++tried;
      const render::Ray ray = rayAtCursor(pixel.x, pixel.y);
      float distance = 0, u = 0, v = 0;
      if (!render::intersectRayTriangle(ray, a, bb, cc, &distance, &u, &v)) return std::nullopt;
      if (!nothingInFront(i, pixel, ray, distance)) return std::nullopt;
      return pixel;
    };
    std::optional<glm::vec2> found;
    if (drawn.grabTriangle < triangleCount) found = grabAt(drawn.grabTriangle);
    // A body hidden at the last write tries a quarter of the candidates per write, going on
    // where the last write stopped: hidden bodies were most of a large scene's grab time.
    const std::size_t budget = drawn.grabMissed ? kGrabCandidates / 4 : kGrabCandidates;
    const std::size_t skip = drawn.grabMissed ? drawn.grabNextCandidate : 0;
    if (!found) {
      drawn.grabTriangle = std::numeric_limits<std::size_t>::max();
      struct Candidate {
        bool backFacing;
        float eyeDistance2;
        std::size_t triangle;
      };
      std::vector<Candidate> candidates;
      candidates.reserve(kGrabSamples + 1);
      const glm::vec3 eye = camera_.eye();
      const std::size_t stride = std::max<std::size_t>(1, triangleCount / kGrabSamples);
      for (std::size_t t = 0; t < triangleCount; t += stride) {
        const glm::vec3 a = corner(t, 0), bb = corner(t, 1), cc = corner(t, 2);
        const glm::vec3 toEye = eye - (a + bb + cc) / 3.0f;
        const bool backFacing = glm::dot(glm::cross(bb - a, cc - a), toEye) <= 0.0f;
        candidates.push_back({backFacing, glm::dot(toEye, toEye), t});
      }
      std::sort(candidates.begin(), candidates.end(), [](const Candidate& u, const Candidate& v) {
        if (u.backFacing != v.backFacing) return v.backFacing;
        return u.eyeDistance2 != v.eyeDistance2 ? u.eyeDistance2 < v.eyeDistance2
                                                : u.triangle < v.triangle;
      });
      std::size_t next = skip < candidates.size() ? skip : 0;  // after the last, the first
      for (; next < candidates.size() && !found && tried < budget; ++next) {
        found = grabAt(candidates[next].triangle);
        if (found) drawn.grabTriangle = candidates[next].triangle;
      }
      drawn.grabNextCandidate = next;
    }
    drawn.grabMissed = !found;
    json grab = nullptr;
    if (found) grab = {static_cast<int>(found->x), static_cast<int>(found->y)};
    b["grabPixel"] = grab;
    bodies.push_back(std::move(b));
  }
  j["bodies"] = std::move(bodies);

  // The text and the file on another thread, while the next frame runs: on the large scene they
  // are ~0.9 ms of a write (the file alone 0.6-0.85 ms on ext4).
  return statsWriter_->post(std::move(j));
}

}  // namespace sb::app
