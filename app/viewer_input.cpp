// Mouse and keyboard: orbit camera, dragging bodies (docs/design.md §5.4), keyboard shortcuts.
//
//   left drag          grab the surface point under the cursor and pull it (soft constraint)
//   Ctrl + left drag   grab the nearest particle instead
//   right drag         orbit;  Shift + right drag or middle drag: pan;  wheel: zoom
//   space pause, S/N single step, R reset, F frame scene, P/C/K/G overlays, arrows orbit,
//   +/- zoom, Esc/Q quit
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include <GLFW/glfw3.h>
#include <imgui.h>

#include "app/viewer_app.h"
#include "render/picking.h"
#include "sim/cage/embedding.h"

namespace sb::app {

namespace {

ViewerApp* appOf(GLFWwindow* window) {
  return static_cast<ViewerApp*>(glfwGetWindowUserPointer(window));
}

bool imguiWantsMouse() {
  return ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse;
}
bool imguiWantsKeyboard() {
  return ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureKeyboard;
}

// Screen radius (pixels) within which Ctrl-click finds a particle.
constexpr float kParticlePickRadius = 40.0f;

}  // namespace

void ViewerApp::installCallbacks() {
  glfwSetMouseButtonCallback(window_, [](GLFWwindow* w, int button, int action, int mods) {
    appOf(w)->onMouseButton(button, action, mods);
  });
  glfwSetCursorPosCallback(window_,
                           [](GLFWwindow* w, double x, double y) { appOf(w)->onCursorPos(x, y); });
  glfwSetScrollCallback(window_,
                        [](GLFWwindow* w, double dx, double dy) { appOf(w)->onScroll(dx, dy); });
  glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int mods) {
    appOf(w)->onKey(key, action, mods);
  });
  glfwSetDropCallback(window_, [](GLFWwindow* w, int count, const char** paths) {
    appOf(w)->onDrop(std::vector<std::string>(paths, paths + count));
  });
  // The window manager's close button asks like Esc/Q does.
  glfwSetWindowCloseCallback(window_, [](GLFWwindow* w) {
    glfwSetWindowShouldClose(w, GLFW_FALSE);
    appOf(w)->requestQuit();
  });
}

ViewerApp::ViewRect ViewerApp::viewRect() const {
  ViewRect r;
  const float panel = options_.hideUi || panelHidden_ ? 0.0f : kPanelWidth;
  const int width = windowWidth_ > 0 ? windowWidth_ : options_.width;
  const int height = windowHeight_ > 0 ? windowHeight_ : options_.height;
  r.x = std::min(panel, static_cast<float>(width) - 1.0f);
  r.width = std::max(static_cast<float>(width) - r.x, 1.0f);
  r.height = static_cast<float>(std::max(height, 1));
  return r;
}

render::Ray ViewerApp::rayAtCursor(double x, double y) const {
  const ViewRect r = viewRect();
  return camera_.rayThroughPixel(static_cast<float>(x) - r.x, static_cast<float>(y) - r.y, r.width,
                                 r.height);
}

bool ViewerApp::projectToWindow(const glm::vec3& point, glm::vec2* pixel) const {
  const ViewRect r = viewRect();
  if (!camera_.project(point, r.width, r.height, pixel)) return false;
  *pixel += glm::vec2(r.x, r.y);
  return true;
}

void ViewerApp::onMouseButton(int button, int action, int mods) {
  double x = 0, y = 0;
  glfwGetCursorPos(window_, &x, &y);
  cursorX_ = x;
  cursorY_ = y;
  glfwGetWindowSize(window_, &windowWidth_, &windowHeight_);
  if (action == GLFW_RELEASE) {
    // Releases always end what a press started, even over the panel.
    if (button == GLFW_MOUSE_BUTTON_LEFT) endDrag();
    if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) {
      orbiting_ = false;
      panning_ = false;
    }
    return;
  }
  if (action != GLFW_PRESS || imguiWantsMouse()) return;
  if (button == GLFW_MOUSE_BUTTON_LEFT) {
    beginDrag(x, y, (mods & GLFW_MOD_CONTROL) != 0);
  } else if (button == GLFW_MOUSE_BUTTON_RIGHT) {
    if (mods & GLFW_MOD_SHIFT)
      panning_ = true;
    else
      orbiting_ = true;
  } else if (button == GLFW_MOUSE_BUTTON_MIDDLE) {
    panning_ = true;
  }
}

void ViewerApp::onCursorPos(double x, double y) {
  const float dx = static_cast<float>(x - cursorX_);
  const float dy = static_cast<float>(y - cursorY_);
  cursorX_ = x;
  cursorY_ = y;
  if (orbiting_) camera_.orbit(dx, dy);
  if (panning_) camera_.pan(dx, dy, static_cast<float>(std::max(windowHeight_, 1)));
  // The drag target follows in updateDragTarget(), once per frame.
}

void ViewerApp::onScroll(double, double dy) {
  if (imguiWantsMouse()) return;
  camera_.zoom(std::pow(0.88f, static_cast<float>(dy)));
}

void ViewerApp::onKey(int key, int action, int mods) {
  if (action == GLFW_RELEASE || imguiWantsKeyboard()) return;
  const bool press = action == GLFW_PRESS;
  switch (key) {
    case GLFW_KEY_SPACE:
      if (press) paused_ = !paused_;
      break;
    case GLFW_KEY_S:
    case GLFW_KEY_N:
      paused_ = true;
      stepOnce_ = true;
      break;
    case GLFW_KEY_R:
      if (press) resetRequested_ = true;
      break;
    case GLFW_KEY_F:
      if (press) frameCamera();
      break;
    case GLFW_KEY_P:
      if (press) showParticles_ = !showParticles_;
      break;
    case GLFW_KEY_C:
      if (press && !(mods & GLFW_MOD_CONTROL)) showCage_ = !showCage_;
      break;
    case GLFW_KEY_K:
      if (press) showClusters_ = !showClusters_;
      break;
    case GLFW_KEY_G:
      if (press) showGoals_ = !showGoals_;
      break;
    case GLFW_KEY_H:
      if (press) panelHidden_ = !panelHidden_;
      break;
    case GLFW_KEY_Z:
      if (press && (mods & GLFW_MOD_CONTROL)) undoParamEdit();
      break;
    case GLFW_KEY_LEFT:
      camera_.orbit(-15.0f, 0.0f);
      break;
    case GLFW_KEY_RIGHT:
      camera_.orbit(15.0f, 0.0f);
      break;
    case GLFW_KEY_UP:
      camera_.orbit(0.0f, 15.0f);
      break;
    case GLFW_KEY_DOWN:
      camera_.orbit(0.0f, -15.0f);
      break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
      camera_.zoom(0.9f);
      break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
      camera_.zoom(1.0f / 0.9f);
      break;
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q:
      if (press) requestQuit();
      break;
    default:
      break;
  }
}

void ViewerApp::beginDrag(double x, double y, bool nearestParticle) {
  endDrag();
  const render::Ray ray = rayAtCursor(x, y);
  World& world = scene_.world;
  Drag drag;
  drag.nearestParticle = nearestParticle;

  if (nearestParticle) {
    // The particle closest to the cursor on screen, within kParticlePickRadius pixels.
    float best = kParticlePickRadius;
    for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
      const ConstPointsRef p = world.positions(scene_.bodies[i].handle);
      for (int k = 0; k < p.rows(); ++k) {
        const glm::vec3 q(p(k, 0), p(k, 1), p(k, 2));
        glm::vec2 pixel;
        if (!projectToWindow(q, &pixel)) continue;
        const float d =
            glm::length(pixel - glm::vec2(static_cast<float>(x), static_cast<float>(y)));
        if (d < best) {
          best = d;
          drag.body = static_cast<int>(i);
          drag.particles = {k};
          drag.weights = {1.0};
          drag.grabPoint = q;
        }
      }
    }
  } else {
    // The surface point under the cursor on the deformed render meshes.
    render::TriangleHit best;
    best.distance = std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < views_.size(); ++i) {
      const BodyView& v = views_[i];
      const render::TriangleHit hit =
          render::pickTriangles(ray, v.vertices.data(), static_cast<std::size_t>(v.vertices.rows()),
                                v.triangles.data(), v.triangles.size() / 3);
      if (hit.hit && hit.distance < best.distance) {
        best = hit;
        drag.body = static_cast<int>(i);
      }
    }
    if (drag.body >= 0) {
      const BodyView& v = views_[drag.body];
      const SceneBody& body = scene_.bodies[drag.body];
      // Weights of the hit point on the particles: the barycentric blend of the three corners'
      // rows of W (or of the corners themselves when the mesh is the particle mesh).
      std::map<int, double> weights;
      std::vector<std::pair<int, double>> rowWeights;
      for (int c = 0; c < 3; ++c) {
        const int vertex = v.triangles[3 * static_cast<std::size_t>(best.triangle) + c];
        const double b = best.barycentric[c];
        if (v.embedded) {
          body.render->embedding->rowWeights(vertex, rowWeights);
          for (const auto& [particle, w] : rowWeights) weights[particle] += b * w;
        } else {
          weights[vertex] += b;
        }
      }
      for (const auto& [particle, w] : weights) {
        if (w == 0.0) continue;
        drag.particles.push_back(particle);
        drag.weights.push_back(w);
      }
      drag.grabPoint = best.point;
    }
  }
  if (drag.body < 0 || drag.particles.empty()) return;

  drag.planePoint = drag.grabPoint;
  drag.planeNormal = camera_.forward();
  drag.target = drag.grabPoint;
  DragDef def;
  def.body = scene_.bodies[drag.body].handle;
  def.particles = drag.particles;
  def.weights = drag.weights;
  def.target = Vec3(drag.target.x, drag.target.y, drag.target.z);
  def.stiffness = dragStiffness_;
  try {
    drag.id = world.addDrag(def);
  } catch (const std::exception& e) {
    errorMessage_ = std::string("cannot drag: ") + e.what();
    return;
  }
  drag.active = true;
  drag_ = std::move(drag);
}

void ViewerApp::updateDragTarget() {
  if (!drag_.active) return;
  glm::vec3 target;
  if (!render::intersectRayPlane(rayAtCursor(cursorX_, cursorY_), drag_.planePoint,
                                 drag_.planeNormal, &target))
    return;
  drag_.target = target;
  scene_.world.setDragTarget(drag_.id, Vec3(target.x, target.y, target.z));
}

void ViewerApp::endDrag() {
  if (!drag_.active) return;
  try {
    scene_.world.removeDrag(drag_.id);
  } catch (const std::exception&) {
    // The world already dropped it (reset, body reset after NaN): nothing to undo.
  }
  drag_ = Drag{};
}

}  // namespace sb::app
