// Adding and removing bodies while the viewer runs: a mesh file dropped on the window (or named
// in the Scene file section) becomes a soft body above the others, with an automatic cage
// (sim/cage/auto_cage.h) unless it is one of the scene's cages itself; any body can be
// duplicated or removed. Bodies are added through the scene library (addSceneBody, or
// prepareSceneBody on another thread and then addPreparedBody for a mesh, whose cage takes
// seconds for a large one), so they are checked like bodies of a scene file and saved like them.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/viewer_app.h"
#include "sim/mesh/mesh_io.h"

namespace sb::app {

namespace {

bool isSceneFile(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".json";
}

}  // namespace

void ViewerApp::onDrop(const std::vector<std::string>& paths) {
  for (const std::string& path : paths) {
    if (isSceneFile(path)) {
      openScene(path);
    } else {
      addBodyFromMesh(path);
    }
  }
}

void ViewerApp::bodiesChanged() {
  endDrag();
  clearPlots();
  rebuildBodyViews();
  updateMeshes();
}

bool ViewerApp::addBodyFromMesh(const std::string& path) {
  try {
    // Sized to a quarter of the scene (0.3 to 2 m across) and dropped from above the highest
    // body at the point the camera looks at: a mesh in millimetres or kilometres arrives usable.
    const mesh::TriangleMesh m = mesh::readMesh(path);
    Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
    for (const Vec3& v : m.vertices) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    const double diagonal = (hi - lo).norm();
    if (!(diagonal > 0.0)) throw std::runtime_error(path + ": the mesh has no extent");
    const double size = std::clamp(0.25 * static_cast<double>(sceneSize_), 0.3, 2.0);
    const double scale = size / diagonal;
    double top = groundHeight();
    for (const BodyView& v : views_) top = std::max(top, static_cast<double>(v.boundsMax.y));
    const Vec3 centre = 0.5 * (lo + hi);
    const Vec3 place(camera_.target.x, top + 0.3 + 0.5 * scale * (hi.y() - lo.y()),
                     camera_.target.z);
    const Vec3 translation = place - scale * centre;
    const std::string name = std::filesystem::path(path).stem().string();
    const nlohmann::json body = {
        {"name", name},
        {"renderMesh", std::filesystem::absolute(path).string()},
        {"cage", {{"auto", true}}},
        {"translation", {translation.x(), translation.y(), translation.z()}},
        {"scale", scale},
        {"mass", 1.0},
        {"mode", "linear"},
        {"alpha", 0.5},
        {"beta", 0.3},
        {"damping", 0.1}};
    // The render mesh's path is absolute: no folder to resolve against.
    pendingBodies_.push_back({name, std::chrono::steady_clock::now(),
                              std::async(std::launch::async, [text = body.dump(), path] {
                                return prepareSceneBody(text, path, "");
                              })});
    errorMessage_.clear();
    statusMessage_ = "adding " + name + ": making its automatic cage";
    return true;
  } catch (const std::exception& e) {
    errorMessage_ = std::string("cannot add a body from ") + path + ": " + e.what();
    return false;
  }
}

void ViewerApp::addPreparedBodies() {
  while (!pendingBodies_.empty() && pendingBodies_.front().prepared.wait_for(
                                        std::chrono::seconds(0)) == std::future_status::ready) {
    PendingBody pending = std::move(pendingBodies_.front());
    pendingBodies_.pop_front();
    try {
      const int index = addPreparedBody(scene_, pending.prepared.get());
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - pending.start).count();
      bodiesChanged();
      const SceneBody& added = scene_.bodies[static_cast<std::size_t>(index)];
      errorMessage_.clear();
      char text[256];
      std::snprintf(text, sizeof text,
                    "added %s: %d particles, an automatic cage of %d vertices (%.1f s), linear "
                    "alpha 0.5",
                    pending.name.c_str(), scene_.world.particleCount(added.handle),
                    added.cageVertexCount, seconds);
      statusMessage_ = text;
    } catch (const std::exception& e) {
      errorMessage_ = "cannot add " + pending.name + ": " + e.what();
      statusMessage_.clear();
    }
  }
}

void ViewerApp::removeBody(int body) {
  const std::string name = scene_.world.name(scene_.bodies[static_cast<std::size_t>(body)].handle);
  endDrag();  // before the body goes: the drag may hold it
  removeSceneBody(scene_, body);
  bodiesChanged();
  statusMessage_ = "removed " + name;
}

void ViewerApp::duplicateBody(int body) {
  try {
    // The body as it would be saved (its parameters and placement in the file), lifted above
    // the highest body.
    nlohmann::json copy = nlohmann::json::parse(sceneText(scene_, scene_.path))["bodies"][body];
    const BodyView& v = views_[static_cast<std::size_t>(body)];
    double top = groundHeight();
    for (const BodyView& other : views_)
      top = std::max(top, static_cast<double>(other.boundsMax.y));
    copy["translation"][1] = copy["translation"][1].get<double>() + (top + 0.3 - v.boundsMin.y);
    copy["name"] = copy["name"].get<std::string>() + " copy";
    addSceneBody(scene_, copy.dump(), scene_.path.empty() ? "duplicate" : scene_.path,
                 std::filesystem::path(scene_.path).parent_path().string());
    bodiesChanged();
    statusMessage_ = "duplicated " + copy["name"].get<std::string>();
  } catch (const std::exception& e) {
    errorMessage_ = std::string("cannot duplicate: ") + e.what();
  }
}

}  // namespace sb::app
