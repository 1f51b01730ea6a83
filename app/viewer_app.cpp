// Viewer window, frame loop and scene drawing. Input lives in viewer_input.cpp, the ImGui panel
// in viewer_ui.cpp, the stats file in viewer_stats.cpp.
#include "app/viewer_app.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <future>
#include <thread>
#include <utility>

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include "app/stats_file_writer.h"
#include "render/capture.h"
#include "render/debug_draw.h"
#include "render/gl.h"
#include "render/ground_renderer.h"
#include "render/mesh_buffer.h"
#include "render/mesh_renderer.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/normals.h"

namespace sb::app {

namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

const glm::vec4 kBodyPalette[] = {
    {0.90f, 0.47f, 0.35f, 1.0f}, {0.36f, 0.62f, 0.92f, 1.0f}, {0.52f, 0.80f, 0.40f, 1.0f},
    {0.92f, 0.76f, 0.30f, 1.0f}, {0.72f, 0.52f, 0.88f, 1.0f}, {0.35f, 0.80f, 0.76f, 1.0f},
};

// A distinct colour per cluster index (golden-ratio hue steps).
glm::vec4 clusterColour(int index) {
  const float hue = std::fmod(0.13f + 0.618034f * static_cast<float>(index), 1.0f);
  const float h6 = hue * 6.0f;
  const float x = 1.0f - std::fabs(std::fmod(h6, 2.0f) - 1.0f);
  glm::vec3 rgb;
  switch (static_cast<int>(h6)) {
    case 0:
      rgb = {1, x, 0};
      break;
    case 1:
      rgb = {x, 1, 0};
      break;
    case 2:
      rgb = {0, 1, x};
      break;
    case 3:
      rgb = {0, x, 1};
      break;
    case 4:
      rgb = {x, 0, 1};
      break;
    default:
      rgb = {1, 0, x};
      break;
  }
  return glm::vec4(0.25f + 0.75f * rgb, 1.0f);
}

glm::vec3 row(ConstPointsRef points, int i) {
  return glm::vec3(points(i, 0), points(i, 1), points(i, 2));
}

glm::vec3 toGlm(const Vec3& v) {
  return glm::vec3(static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z()));
}

}  // namespace

ViewerApp::ViewerApp(const ViewerOptions& options, Scene scene)
    : options_(options), scene_(std::move(scene)) {
  paused_ = options_.startPaused;
  const std::string show = "," + options_.show + ",";
  showParticles_ = show.find(",particles,") != std::string::npos;
  showCage_ = show.find(",cage,") != std::string::npos;
  showClusters_ = show.find(",clusters,") != std::string::npos;
  showGoals_ = show.find(",goals,") != std::string::npos;
  foldCheck_ = show.find(",folds,") != std::string::npos;
  scenePathInput_ = scene_.path;
  savePathInput_ = savePathFor(scene_.path);
  savedText_ = sceneText(scene_, scene_.path);
  rememberFileParams();
  screenshotPathInput_ = "softbody_screenshot.png";
  if (!options_.statsPath.empty())
    statsWriter_ = std::make_unique<StatsFileWriter>(options_.statsPath);
}

ViewerApp::~ViewerApp() {
  if (window_) glfwMakeContextCurrent(window_);
  // GL objects go before the context does.
  views_.clear();
  meshRenderer_.reset();
  groundRenderer_.reset();
  debugDraw_.reset();
  overlayDraw_.reset();
  if (imguiReady_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  if (window_) glfwDestroyWindow(window_);
}

bool ViewerApp::open(std::string* error) {
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
  const std::string title =
      "softbody - " + (scene_.path.empty() ? std::string("scene") : scene_.path);
  window_ = glfwCreateWindow(options_.width, options_.height, title.c_str(), nullptr, nullptr);
  if (!window_) {
    *error = "cannot create a " + std::to_string(options_.width) + "x" +
             std::to_string(options_.height) + " window with an OpenGL 3.3 core context";
    return false;
  }
  // A fixed place on the screen, so tests can send mouse events to known pixels.
  glfwSetWindowPos(window_, 0, 0);
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(0);  // the frame cap below paces frames (vsync does nothing under Xvfb)
  glfwSetWindowUserPointer(window_, this);
  installCallbacks();  // before ImGui, which chains to them

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini: the layout is fixed and tests must not depend on one
  ImGui::StyleColorsDark();
  ImGui::GetStyle().WindowRounding = 0.0f;
  // The panel's background is not drawn by ImGui (a blended full-height quad is expensive on
  // llvmpipe): renderFrame clears the panel's rectangle to this colour instead.
  ImVec4& panelBackground = ImGui::GetStyle().Colors[ImGuiCol_WindowBg];
  panelColour_ = glm::vec3(panelBackground.x, panelBackground.y, panelBackground.z);
  panelBackground.w = 0.0f;
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imguiReady_ = true;

  try {
    meshRenderer_ = std::make_unique<render::MeshRenderer>();
    groundRenderer_ = std::make_unique<render::GroundRenderer>();
    debugDraw_ = std::make_unique<render::DebugDraw>();
    overlayDraw_ = std::make_unique<render::DebugDraw>();
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  rebuildBodyViews();
  updateMeshes();
  frameCamera();
  return true;
}

void ViewerApp::rebuildBodyViews() {
  meshesCurrent_ = false;
  // Body indices may have changed: the fold watch and a pending switch refer to the old ones.
  clearFolds();
  embeddingRequest_ = EmbeddingRequest{};
  views_.clear();
  views_.resize(scene_.bodies.size());
  for (std::size_t i = 0; i < views_.size(); ++i) {
    BodyView& v = views_[i];
    const SceneBody& body = scene_.bodies[i];
    const auto& tris = scene_.renderTriangles(static_cast<int>(i));
    v.triangles.resize(tris.size() * 3);
    for (std::size_t t = 0; t < tris.size(); ++t)
      for (int c = 0; c < 3; ++c) v.triangles[3 * t + c] = tris[t][c];
    v.embedded = body.render && body.render->embedding;
    v.mesh = std::make_unique<render::MeshBuffer>();
    v.mesh->setIndices(v.triangles.data(), tris.size());
    v.colour = kBodyPalette[i % (sizeof kBodyPalette / sizeof kBodyPalette[0])];
    // Unique cage edges, in a fixed order.
    const int particles = scene_.world.particleCount(body.handle);
    v.cageEdges.clear();
    for (const auto& e : mesh::buildSurfaceTopology(body.cageTriangles, particles).edges)
      v.cageEdges.push_back({e[0], e[1]});
    refreshClusters(static_cast<int>(i));
    syncEmbeddingEdits(static_cast<int>(i));
  }
}

void ViewerApp::refreshClusters(int body) {
  views_[body].clusters = scene_.world.clusterMembers(scene_.bodies[body].handle);
}

void ViewerApp::frameCamera() {
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const BodyView& v : views_) {
    lo = glm::min(lo, v.boundsMin);
    hi = glm::max(hi, v.boundsMax);
  }
  // Static colliders other than planes belong to the scene too.
  for (const Collider& c : scene_.world.colliders()) {
    Vec3 half = Vec3::Zero();
    const Vec3 centre = c.centre;
    switch (c.shape) {
      case Collider::Shape::Plane:
        continue;
      case Collider::Shape::Box:
        half = c.rotation.cwiseAbs() * c.halfExtents;
        break;
      case Collider::Shape::Sphere:
        half = Vec3::Constant(c.radius);
        break;
      case Collider::Shape::Capsule:
        half = c.axis.cwiseAbs() + Vec3::Constant(c.radius);
        break;
    }
    lo = glm::min(lo, toGlm(centre - half));
    hi = glm::max(hi, toGlm(centre + half));
  }
  if (lo.x > hi.x) {
    lo = glm::vec3(-1.0f);
    hi = glm::vec3(1.0f);
  }
  // Keep the ground in view below the bodies.
  lo.y = std::min(lo.y, groundHeight());
  sceneSize_ = std::max(glm::length(hi - lo), 1e-3f);
  camera_.yaw = 0.45f;
  camera_.pitch = 0.42f;
  camera_.frame(lo, hi);
  camera_.nearPlane = 0.01f * sceneSize_;
  camera_.farPlane = 200.0f * sceneSize_;
}

float ViewerApp::groundHeight() const {
  // The first plane facing up is the ground (normal·x < offset is solid: y = offset).
  for (const Collider& c : scene_.world.colliders())
    if (c.shape == Collider::Shape::Plane && c.normal.y() > 0.99)
      return static_cast<float>(c.offset / c.normal.y());
  float lowest = 0.0f;
  bool any = false;
  for (const BodyView& v : views_) {
    lowest = any ? std::min(lowest, v.boundsMin.y) : v.boundsMin.y;
    any = true;
  }
  return lowest;
}

double ViewerApp::timedStep() {
  const Clock::time_point start = Clock::now();
  for (int k = 0; k < stepsPerFrame_; ++k) {
    scene_.world.step();
    timings_.phaseSum += scene_.world.lastProfile();
    ++timings_.steps;
  }
  return millisecondsSince(start);
}

void ViewerApp::collectEvents() {
  for (const WorldEvent& e : scene_.world.takeEvents()) {
    std::string who = scene_.world.contains(e.body) ? scene_.world.name(e.body) : "world";
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "[t=%.2fs] ", scene_.world.time());
    eventLog_.push_front(stamp + who + ": " + e.message);
    std::fprintf(stderr, "softbody: %s: %s\n", who.c_str(), e.message.c_str());
    ++eventCount_;
    if (drag_.active && drag_.body >= 0 && scene_.bodies[drag_.body].handle == e.body) endDrag();
  }
  while (eventLog_.size() > 50) eventLog_.pop_back();
}

void ViewerApp::resetSimulation() {
  drag_ = Drag{};  // World::reset clears drags
  scene_.world.reset();
  meshesCurrent_ = false;
  collectEvents();
  for (std::size_t i = 0; i < views_.size(); ++i) refreshClusters(static_cast<int>(i));
  clearPlots();
  lastFoldCheck_ = -1;
  statusMessage_ = "reset";
}

void ViewerApp::updateMeshes() {
  meshesCurrent_ = true;
  std::vector<int> stale;
  std::vector<PointsRowMajor*> outs;
  for (std::size_t i = 0; i < views_.size(); ++i)
    if (scene_.renderVerticesStale(static_cast<int>(i), views_[i].currentWhileAsleep)) {
      stale.push_back(static_cast<int>(i));
      outs.push_back(&views_[i].vertices);
    }
  scene_.renderVertices(stale, outs);
  // Each stale body's normals and bounds (its own view only), the bodies split in two runs of
  // about equal vertex counts, the second on another thread when there are many vertices (the
  // simulation's pool has one thread in the viewer, and nothing else runs here: the step starts
  // after this). The seed-scale scene's 577k vertices took 14 ms here on one thread, 8.5 on two
  // (under Xvfb on the 2-core VM), against 3.3 ms for their deform.
  auto finish = [&](std::size_t begin, std::size_t end) {
    for (std::size_t s = begin; s < end; ++s) {
      const int i = stale[s];
      BodyView& v = views_[static_cast<std::size_t>(i)];
      v.uploaded = false;
      const auto n = static_cast<std::size_t>(v.vertices.rows());
      // The cage module's normals (area weighted, unit); a vertex no triangle uses gets +y so
      // the shader never normalises a zero vector.
      PointsRowMajor normals;
      mesh::computeVertexNormals(scene_.renderTriangles(i), v.vertices, normals);
      v.normals.resize(n * 3);
      for (std::size_t k = 0; k < n; ++k) {
        Eigen::RowVector3f nk = normals.row(static_cast<Eigen::Index>(k));
        if (!(nk.squaredNorm() > 0.0f)) nk = Eigen::RowVector3f(0.0f, 1.0f, 0.0f);
        for (int a = 0; a < 3; ++a) v.normals[3 * k + static_cast<std::size_t>(a)] = nk[a];
      }
      if (n > 0) {
        const Eigen::RowVector3f lo = v.vertices.colwise().minCoeff();
        const Eigen::RowVector3f hi = v.vertices.colwise().maxCoeff();
        v.boundsMin = glm::vec3(lo(0), lo(1), lo(2));
        v.boundsMax = glm::vec3(hi(0), hi(1), hi(2));
      }
    }
  };
  constexpr Eigen::Index kSecondThreadVertices = 50000;
  Eigen::Index total = 0;
  for (const PointsRowMajor* out : outs) total += out->rows();
  if (total < kSecondThreadVertices || stale.size() < 2 ||
      std::thread::hardware_concurrency() < 2) {
    finish(0, stale.size());
    return;
  }
  std::size_t half = 0;
  for (Eigen::Index sum = 0; half < stale.size() && 2 * sum < total; ++half)
    sum += outs[half]->rows();
  std::future<void> second = std::async(std::launch::async, finish, half, stale.size());
  finish(0, half);
  second.get();
}

void ViewerApp::drawColliders(render::DebugDraw& draw) {
  const glm::vec4 colour(0.8f, 0.8f, 0.85f, 0.9f);
  auto circle = [&](const glm::vec3& centre, const glm::vec3& a, const glm::vec3& b, float r) {
    constexpr int kSegments = 48;
    for (int s = 0; s < kSegments; ++s) {
      const float t0 = 6.2831853f * static_cast<float>(s) / kSegments;
      const float t1 = 6.2831853f * static_cast<float>(s + 1) / kSegments;
      draw.line(centre + r * (std::cos(t0) * a + std::sin(t0) * b),
                centre + r * (std::cos(t1) * a + std::sin(t1) * b), colour);
    }
  };
  const glm::vec3 ex(1, 0, 0), ey(0, 1, 0), ez(0, 0, 1);
  for (const Collider& c : scene_.world.colliders()) {
    const glm::vec3 centre = toGlm(c.centre);
    switch (c.shape) {
      case Collider::Shape::Plane:
        break;  // the ground is drawn as a checkerboard
      case Collider::Shape::Box: {
        glm::vec3 corner[8];
        for (int k = 0; k < 8; ++k) {
          const Vec3 local((k & 1 ? 1 : -1) * c.halfExtents.x(),
                           (k & 2 ? 1 : -1) * c.halfExtents.y(),
                           (k & 4 ? 1 : -1) * c.halfExtents.z());
          corner[k] = toGlm(c.centre + c.rotation * local);
        }
        for (int k = 0; k < 8; ++k)
          for (int bit = 1; bit < 8; bit <<= 1)
            if (!(k & bit)) draw.line(corner[k], corner[k | bit], colour);
        break;
      }
      case Collider::Shape::Sphere: {
        const float r = static_cast<float>(c.radius);
        circle(centre, ex, ey, r);
        circle(centre, ey, ez, r);
        circle(centre, ez, ex, r);
        break;
      }
      case Collider::Shape::Capsule: {
        const glm::vec3 axis = toGlm(c.axis);
        const float r = static_cast<float>(c.radius);
        const glm::vec3 along = glm::length(axis) > 0 ? glm::normalize(axis) : ey;
        glm::vec3 side = glm::cross(along, std::fabs(along.y) < 0.9f ? ey : ex);
        side = glm::normalize(side);
        const glm::vec3 side2 = glm::cross(along, side);
        for (float s : {-1.0f, 1.0f}) circle(centre + s * axis, side, side2, r);
        for (const glm::vec3& d : {side, -side, side2, -side2})
          draw.line(centre - axis + r * d, centre + axis + r * d, colour);
        break;
      }
    }
  }
}

void ViewerApp::drawOverlays(render::DebugDraw& draw) {
  World& world = scene_.world;
  for (std::size_t i = 0; i < views_.size(); ++i) {
    const BodyView& v = views_[i];
    const BodyHandle h = scene_.bodies[i].handle;
    const ConstPointsRef x = world.positions(h);
    if (showCage_) {
      const glm::vec4 colour = glm::mix(v.colour, glm::vec4(1.0f), 0.5f);
      for (const auto& e : v.cageEdges)
        if (e.first < x.rows() && e.second < x.rows())
          draw.line(row(x, e.first), row(x, e.second), colour);
    }
    if (showClusters_) {
      for (std::size_t c = 0; c < v.clusters.size(); ++c) {
        const glm::vec4 colour = clusterColour(static_cast<int>(c));
        glm::vec3 centre(0.0f);
        for (int p : v.clusters[c]) centre += row(x, p);
        centre /= std::max<float>(1.0f, static_cast<float>(v.clusters[c].size()));
        for (int p : v.clusters[c])
          draw.line(centre, row(x, p), glm::vec4(glm::vec3(colour), 0.55f));
        draw.point(centre, colour);
      }
    }
    if (showGoals_) {
      const Eigen::MatrixX3d goals = world.goals(h);
      for (int p = 0; p < goals.rows() && p < x.rows(); ++p) {
        const glm::vec3 g(static_cast<float>(goals(p, 0)), static_cast<float>(goals(p, 1)),
                          static_cast<float>(goals(p, 2)));
        draw.line(row(x, p), g, glm::vec4(1.0f, 0.9f, 0.2f, 0.7f));
        draw.point(g, glm::vec4(1.0f, 0.9f, 0.2f, 1.0f));
      }
    }
    if (showParticles_)
      for (int p = 0; p < x.rows(); ++p) draw.point(row(x, p), glm::vec4(0.95f, 0.95f, 1.0f, 1.0f));
  }
  if (drag_.active && drag_.body >= 0) {
    const ConstPointsRef x = world.positions(scene_.bodies[drag_.body].handle);
    glm::vec3 point(0.0f);
    for (std::size_t k = 0; k < drag_.particles.size(); ++k)
      point += static_cast<float>(drag_.weights[k]) * row(x, drag_.particles[k]);
    draw.line(point, drag_.target, glm::vec4(1.0f, 0.25f, 0.2f, 1.0f));
    draw.point(point, glm::vec4(1.0f, 0.25f, 0.2f, 1.0f));
    draw.point(drag_.target, glm::vec4(1.0f, 1.0f, 1.0f, 1.0f));
  }
}

void ViewerApp::queueLinesAndPoints() {
  frameGroundHeight_ = groundHeight();
  if (showColliders_) drawColliders(*debugDraw_);
  drawOverlays(*overlayDraw_);
}

void ViewerApp::renderFrame() {
  glViewport(0, 0, framebufferWidth_, framebufferHeight_);
  glClearColor(0.16f, 0.17f, 0.20f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  // The scene is drawn right of the panel only: fewer pixels to shade.
  const ViewRect rect = viewRect();
  const float toFramebuffer =
      static_cast<float>(framebufferWidth_) / static_cast<float>(std::max(windowWidth_, 1));
  if (rect.x > 0.0f) {  // the panel's background
    glEnable(GL_SCISSOR_TEST);
    glScissor(0, 0, static_cast<GLsizei>(rect.x * toFramebuffer), framebufferHeight_);
    glClearColor(panelColour_.r, panelColour_.g, panelColour_.b, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glDisable(GL_SCISSOR_TEST);
  }
  glViewport(static_cast<GLint>(rect.x * toFramebuffer), 0,
             static_cast<GLsizei>(rect.width * toFramebuffer),
             static_cast<GLsizei>(rect.height * toFramebuffer));
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);

  const float aspect = rect.width / rect.height;
  const glm::mat4 view = camera_.view();
  const glm::mat4 projection = camera_.projection(aspect);
  const glm::mat4 viewProjection = projection * view;
  const glm::vec3 eye = camera_.eye();

  // A checker square of 1, 2 or 5 × 10^k metres, about a fifth of the scene.
  const float raw = std::max(sceneSize_ / 5.0f, 1e-4f);
  const float decade = std::pow(10.0f, std::floor(std::log10(raw)));
  const float mantissa = raw / decade;
  const float cell = decade * (mantissa < 1.5f ? 1.0f : mantissa < 3.5f ? 2.0f : 5.0f);
  groundRenderer_->draw(viewProjection, eye, frameGroundHeight_, cell, 5.0f * sceneSize_);

  meshRenderer_->begin(view, projection, eye);
  // Closed, outward-oriented meshes: culling back faces halves llvmpipe's triangle work.
  if (cullBackFaces_) glEnable(GL_CULL_FACE);
  for (BodyView& v : views_) {
    if (!v.uploaded)
      v.mesh->setVertices(v.vertices.data(), v.normals.data(),
                          static_cast<std::size_t>(v.vertices.rows()));
    v.uploaded = true;
    if (!options_.hideBodies) meshRenderer_->draw(*v.mesh, v.colour);
  }
  glDisable(GL_CULL_FACE);
  drawFoldTint();
  debugDraw_->flush(viewProjection, 1.0f, true);
  overlayDraw_->flush(viewProjection, 6.0f, !(showParticles_ || showGoals_));
  glViewport(0, 0, framebufferWidth_, framebufferHeight_);
}

bool ViewerApp::takeScreenshot(const std::string& path) {
  std::string error;
  if (!render::captureFramebufferToPng(framebufferWidth_, framebufferHeight_, path, &error)) {
    errorMessage_ = "screenshot: " + error;
    std::fprintf(stderr, "softbody: %s\n", errorMessage_.c_str());
    return false;
  }
  statusMessage_ = "screenshot written to " + path;
  std::printf("softbody: screenshot written to %s\n", path.c_str());
  return true;
}

bool ViewerApp::openScene(const std::string& path) {
  try {
    Scene loaded = loadScene(path);
    // Bodies still being prepared were meant for the scene being closed (waits for them).
    pendingBodies_.clear();
    endDrag();
    scene_ = std::move(loaded);
    rebuildBodyViews();
    updateMeshes();
    frameCamera();
    errorMessage_.clear();
    statusMessage_ = "opened " + path;
    savePathInput_ = savePathFor(path);
    savedText_ = sceneText(scene_, scene_.path);
    rememberFileParams();
    paramUndo_.clear();  // its handles were the old scene's
    clearPlots();
    if (window_) glfwSetWindowTitle(window_, ("softbody - " + path).c_str());
    return true;
  } catch (const std::exception& e) {
    // The current scene keeps running.
    errorMessage_ = std::string("cannot open scene: ") + e.what();
    std::fprintf(stderr, "softbody: %s\n", errorMessage_.c_str());
    return false;
  }
}

std::string ViewerApp::savePathFor(const std::string& scenePath) {
  if (!isShippedScene(scenePath)) return scenePath;
  return (std::filesystem::current_path() /
          (std::filesystem::path(scenePath).stem().string() + "-edited.json"))
      .string();
}

bool ViewerApp::saveCurrentScene(const std::string& path) {
  if (isShippedScene(path) && !overwriteShipped_) {
    errorMessage_ = "cannot save scene: " + path +
                    " is a shipped scene, read-only here: save it under another name (or tick "
                    "'overwrite shipped scenes')";
    return false;
  }
  try {
    saveScene(scene_, path);
    errorMessage_.clear();
    statusMessage_ = "saved " + path;
    savedText_ = sceneText(scene_, scene_.path);
    rememberFileParams();
    return true;
  } catch (const std::exception& e) {
    errorMessage_ = std::string("cannot save scene: ") + e.what();
    return false;
  }
}

bool ViewerApp::hasUnsavedChanges() const {
  return sceneText(scene_, scene_.path) != savedText_;
}

void ViewerApp::requestQuit() {
  if (hasUnsavedChanges()) {
    quitDialog_ = true;
  } else {
    quit();
  }
}

void ViewerApp::quit() {
  glfwSetWindowShouldClose(window_, GLFW_TRUE);
}

bool ViewerApp::timedStatsWrite() {
  const Clock::time_point start = Clock::now();
  const bool written = writeStats();
  statsMsSum_ += millisecondsSince(start);
  ++statsWrites_;
  return written;
}

int ViewerApp::run() {
  start_ = Clock::now();
  Clock::time_point nextFrame = start_;
  Clock::time_point lastFrameStart = start_;
  const long screenshotFrame = options_.frames > 0 ? options_.frames - 1 : 119;

  while (!glfwWindowShouldClose(window_)) {
    const Clock::time_point frameStart = Clock::now();
    if (frame_ > 0) {
      timings_.lastFrame =
          std::chrono::duration<double, std::milli>(frameStart - lastFrameStart).count();
      timings_.frameSum += timings_.lastFrame;
    }
    lastFrameStart = frameStart;

    glfwPollEvents();
    glfwGetFramebufferSize(window_, &framebufferWidth_, &framebufferHeight_);
    glfwGetWindowSize(window_, &windowWidth_, &windowHeight_);

    // The panel first: its edits apply to this frame's step.
    const Clock::time_point uiStart = Clock::now();
    if (!options_.hideUi) {
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();
      drawUi();
      ImGui::Render();
    }
    double renderMs = millisecondsSince(uiStart);
    if (resetRequested_) {
      resetRequested_ = false;
      resetSimulation();
    }
    // The body buttons act after the panel is drawn (the panel walks the bodies).
    if (removeRequest_ >= 0) removeBody(std::exchange(removeRequest_, -1));
    if (duplicateRequest_ >= 0) duplicateBody(std::exchange(duplicateRequest_, -1));
    addPreparedBodies();
    // A switch asked for in an earlier frame: that frame showed "binding ..." (this blocks).
    if (embeddingRequest_.body >= 0 && embeddingRequest_.frame < frame_) applyEmbeddingRequest();

    // The frame's step runs on a second thread while this one draws (llvmpipe leaves a core
    // mostly idle): the frame then shows the state before its step, one frame of latency. The
    // drawing reads no World data: the overlays are queued before the step starts. Frames that
    // must show what the stats file says run the step first, as without overlap: a screenshot's
    // frame and the last frame of --frames (whose stats are written at exit).
    const bool stepping = !paused_ || stepOnce_;
    stepOnce_ = false;
    const bool screenshotDue =
        (!options_.screenshot.empty() && frame_ == screenshotFrame) || !screenshotRequest_.empty();
    const bool lastFrame = options_.frames > 0 && frame_ + 1 >= options_.frames;
    const bool overlap = stepping && options_.overlapStep && !screenshotDue && !lastFrame;
    updateDragTarget();
    if (stepping && !overlap) {
      timings_.lastSim = timedStep();
      collectEvents();
      samplePlots();
      meshesCurrent_ = false;
    } else if (!stepping) {
      timings_.lastSim = 0.0;
    }

    const Clock::time_point deformStart = Clock::now();
    const bool deformed = !meshesCurrent_;  // a paused viewer deforms nothing
    if (deformed) updateMeshes();
    const bool checked = updateFoldCheck();
    timings_.lastDeform = deformed || checked ? millisecondsSince(deformStart) : 0.0;
    queueLinesAndPoints();

    std::future<double> step;
    if (overlap) step = std::async(std::launch::async, [this] { return timedStep(); });
    const Clock::time_point renderStart = Clock::now();
    if (framebufferWidth_ > 0 && framebufferHeight_ > 0) {
      renderFrame();
      if (!options_.hideUi) ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      if (!options_.screenshot.empty() && frame_ == screenshotFrame &&
          !takeScreenshot(options_.screenshot))
        outputFailed_ = true;
      if (!screenshotRequest_.empty()) {
        takeScreenshot(screenshotRequest_);
        screenshotRequest_.clear();
      }
      glfwSwapBuffers(window_);
    }
    renderMs += millisecondsSince(renderStart);
    timings_.lastRender = renderMs;
    if (overlap) {
      timings_.lastSim = step.get();  // rethrows what the step threw
      collectEvents();
      samplePlots();
      meshesCurrent_ = false;
    }

    timings_.simSum += timings_.lastSim;
    timings_.deformSum += timings_.lastDeform;
    timings_.renderSum += timings_.lastRender;
    const int slot = timings_.cursor;
    timings_.simHistory[slot] = static_cast<float>(timings_.lastSim);
    timings_.deformHistory[slot] = static_cast<float>(timings_.lastDeform);
    timings_.renderHistory[slot] = static_cast<float>(timings_.lastRender);
    timings_.frameHistory[slot] = static_cast<float>(timings_.lastFrame);
    timings_.cursor = (slot + 1) % FrameTimings::kHistory;
    ++timings_.frames;
    ++frame_;

    if (!options_.statsPath.empty() && options_.statsEvery > 0 &&
        frame_ % options_.statsEvery == 0 && !timedStatsWrite())
      outputFailed_ = true;
    if (options_.frames > 0 && frame_ >= options_.frames)
      glfwSetWindowShouldClose(window_, GLFW_TRUE);

    // The cap may change in the panel at any time.
    if (options_.fpsCap > 0.0) {
      const auto period = std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>(1.0 / options_.fpsCap));
      nextFrame += period;
      const Clock::time_point now = Clock::now();
      if (nextFrame < now - period) nextFrame = now;  // fell behind: do not try to catch up
      std::this_thread::sleep_until(nextFrame);
    }
  }
  endDrag();
  if (statsWriter_ && !(timedStatsWrite() && statsWriter_->finish())) outputFailed_ = true;
  const double seconds = std::chrono::duration<double>(Clock::now() - start_).count();
  const double frames = static_cast<double>(std::max<long>(timings_.frames, 1));
  std::printf(
      "softbody: %ld frames in %.2f s (%.1f fps); per frame: simulation %.3f ms, deform %.3f ms, "
      "render %.3f ms\n",
      timings_.frames, seconds, static_cast<double>(timings_.frames) / std::max(seconds, 1e-9),
      timings_.simSum / frames, timings_.deformSum / frames, timings_.renderSum / frames);
  if (statsWrites_ > 0)
    std::printf("softbody: %ld stats file writes, %.3f ms each on the frame's thread\n",
                statsWrites_, statsMsSum_ / static_cast<double>(statsWrites_));
  if (outputFailed_) {
    std::fprintf(stderr,
                 "softbody: an output asked for on the command line could not be written "
                 "(see above)\n");
    return 1;
  }
  return 0;
}

}  // namespace sb::app
