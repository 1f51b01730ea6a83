// The --stats JSON file: timings (averages per frame), each body's centre and screen bounds, a
// pixel that hits each body, the Pause checkbox's rectangle and the camera. Tests read it; it
// is rewritten atomically (temporary file + rename) every options.statsEvery frames and at exit.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>

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
  json bodies = json::array();
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    const BodyView& v = views_[i];
    const BodyHandle handle = scene_.bodies[i].handle;
    const Vec3 c = scene_.world.centreOfMass(handle);
    json b;
    b["name"] = scene_.world.name(handle);
    const BodyParams& params = scene_.world.params(handle);
    b["params"] = {{"alpha", params.alpha}, {"beta", params.beta}};
    b["centre"] = {c.x(), c.y(), c.z()};
    // Screen bounds of the projected render vertices (window pixels, origin top left).
    glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (Eigen::Index r = 0; r < v.vertices.rows(); ++r) {
      glm::vec2 pixel;
      if (projectToWindow(glm::vec3(v.vertices(r, 0), v.vertices(r, 1), v.vertices(r, 2)),
                          &pixel)) {
        lo = glm::min(lo, pixel);
        hi = glm::max(hi, pixel);
      }
    }
    b["screenBounds"] = {lo.x, lo.y, hi.x, hi.y};
    glm::vec2 centrePixel(-1.0f);
    projectToWindow(glm::vec3(c.x(), c.y(), c.z()), &centrePixel);
    b["screenCentre"] = {centrePixel.x, centrePixel.y};
    // A pixel whose ray hits this body first: search outward from the projected centre.
    json grab = nullptr;
    for (int ring = 0; ring < 40 && grab.is_null(); ++ring) {
      for (int k = 0; k < std::max(1, 8 * ring) && grab.is_null(); ++k) {
        const float angle =
            6.2831853f * static_cast<float>(k) / static_cast<float>(std::max(1, 8 * ring));
        const glm::vec2 pixel = centrePixel + 4.0f * static_cast<float>(ring) *
                                                  glm::vec2(std::cos(angle), std::sin(angle));
        if (pixel.x < 0 || pixel.y < 0 || pixel.x >= w || pixel.y >= h) continue;
        if (pixel.x < viewRect().x + 4.0f) continue;  // under the panel
        const render::Ray ray = rayAtCursor(pixel.x, pixel.y);
        int nearest = -1;
        float best = std::numeric_limits<float>::infinity();
        for (std::size_t o = 0; o < views_.size(); ++o) {
          const render::TriangleHit hit = render::pickTriangles(
              ray, views_[o].vertices.data(), static_cast<std::size_t>(views_[o].vertices.rows()),
              views_[o].triangles.data(), views_[o].triangles.size() / 3);
          if (hit.hit && hit.distance < best) {
            best = hit.distance;
            nearest = static_cast<int>(o);
          }
        }
        if (nearest == static_cast<int>(i))
          grab = {static_cast<int>(pixel.x), static_cast<int>(pixel.y)};
      }
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
