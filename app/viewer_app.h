// The interactive viewer: a GLFW window showing a Scene, stepping its World every frame, with
// an orbit camera, mouse dragging of bodies and an ImGui control panel.
//
// The class is split over files by concern: viewer_app.cpp (window, frame loop, drawing),
// viewer_input.cpp (mouse, keyboard, camera, dragging), viewer_ui.cpp (ImGui panel),
// viewer_stats.cpp (the --stats JSON file), viewer_embedding.cpp (switching a body's
// embedding), viewer_folds.cpp (the fold check and its tint).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <future>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "app/plot_history.h"
#include "app/viewer_options.h"
#include "render/orbit_camera.h"
#include "sim/scene/fold_watch.h"
#include "sim/scene/scene.h"

struct GLFWwindow;

namespace sb::render {
class MeshBuffer;
class MeshRenderer;
class GroundRenderer;
class DebugDraw;
}  // namespace sb::render

namespace sb::app {

class StatsFileWriter;

// What the viewer keeps per body to draw and pick it.
struct BodyView {
  std::vector<std::int32_t> triangles;  // #T×3 flat, the scene's renderTriangles(i)
  PointsRowMajor vertices;              // deformed render vertices of this frame, #V×3
  std::vector<float> normals;           // smooth normals of this frame, #V×3 flat
  std::unique_ptr<render::MeshBuffer> mesh;
  std::vector<std::pair<int, int>> cageEdges;  // unique edges of the particle mesh
  std::vector<std::vector<int>> clusters;      // cached World::clusterMembers
  bool embedded = false;  // render vertices come from the cage embedding (else = particles)
  glm::vec4 colour{1.0f};
  glm::vec3 boundsMin{0.0f}, boundsMax{0.0f};  // of this frame's vertices
  // The vertices were deformed while the body slept (Scene::renderVerticesStale): neither
  // deform nor upload is redone until it wakes.
  bool currentWhileAsleep = false;
  bool uploaded = false;  // the GPU buffer holds these vertices and normals
  // The embedding controls' values being edited (viewer_embedding.cpp): set from the body's
  // method whenever it changes or a switch is refused.
  int editResolution = 32;
  float editShape = 1.0f;
  std::string embeddingError;       // the last refused switch, shown under the control
  bool showEmbeddingError = false;  // scroll the panel to the error once, when it is new
  // Fold tint (viewer_folds.cpp): triangles touching a render vertex near a folded sample,
  // drawn again over the body in the fold colour.
  std::vector<std::int32_t> tintTriangles;  // #T×3 flat
  int tintedVertices = 0;
  std::unique_ptr<render::MeshBuffer> tint;
  bool tintUploaded = false;
  // The triangle whose centroid gave the last --stats grab pixel (none: SIZE_MAX); the next write
  // tries it first.
  std::size_t grabTriangle = std::numeric_limits<std::size_t>::max();
  // When the last write found no grab pixel (the body is hidden), where in its list of candidate
  // triangles the next write goes on: a hidden body tries a few candidates per write in turn
  // instead of all of them every write.
  std::size_t grabNextCandidate = 0;
  bool grabMissed = false;
};

// Rolling timing figures, milliseconds.
struct FrameTimings {
  static constexpr int kHistory = 180;
  std::array<float, kHistory> simHistory{}, deformHistory{}, renderHistory{}, frameHistory{};
  int cursor = 0;
  // Sums since start (for the averages in the stats file).
  double simSum = 0, deformSum = 0, renderSum = 0, frameSum = 0;
  StepProfile phaseSum;  // seconds
  long frames = 0, steps = 0;
  // Last frame.
  double lastSim = 0, lastDeform = 0, lastRender = 0, lastFrame = 0;
};

// Width of the ImGui control panel on the left of the window, pixels.
constexpr float kPanelWidth = 340.0f;

class ViewerApp {
 public:
  ViewerApp(const ViewerOptions& options, Scene scene);
  ~ViewerApp();
  ViewerApp(const ViewerApp&) = delete;
  ViewerApp& operator=(const ViewerApp&) = delete;

  // Creates the window, GL objects and ImGui. Returns false with *error on failure.
  bool open(std::string* error);
  // Runs until the window is closed or options.frames frames were shown. Returns the exit code.
  int run();

 private:
  // ---- viewer_app.cpp ----
  void rebuildBodyViews();
  void refreshClusters(int body);
  void frameCamera();
  // The frame's World steps; returns their wall time in ms. May run on a second thread while
  // renderFrame draws: touches only the World and the step counters of timings_.
  double timedStep();
  void updateMeshes();
  // Everything renderFrame draws from World data, queued before the step starts: collider
  // lines (debugDraw_), overlays (overlayDraw_), the ground height.
  void queueLinesAndPoints();
  // Draws views_ and the queued lines and points; reads no World data (see timedStep).
  void renderFrame();
  void drawOverlays(render::DebugDraw& draw);
  void drawColliders(render::DebugDraw& draw);
  bool openScene(const std::string& path);
  // Saves to `path`; a shipped scene (isShippedScene) only while overwriteShipped_ is ticked.
  // Returns whether it saved (else errorMessage_ says why).
  bool saveCurrentScene(const std::string& path);
  // Settings or parameters differ from those last opened or saved.
  bool hasUnsavedChanges() const;
  // Esc, Q or the window's close button: quits, or first asks when there are unsaved changes.
  void requestQuit();
  void quit();  // closes the window: run() returns after this frame
  // Where Save writes by default: the scene itself, or for a shipped scene NAME-edited.json in
  // the current folder.
  static std::string savePathFor(const std::string& scenePath);
  bool takeScreenshot(const std::string& path);
  void collectEvents();
  void resetSimulation();
  float groundHeight() const;

  // ---- viewer_bodies.cpp ----
  // Files dropped on the window: scene files are opened, anything else added as a mesh body.
  void onDrop(const std::vector<std::string>& paths);
  // A soft body (linear, automatic cage) from the mesh file, sized and placed above the scene.
  // The cage and the binding are made on another thread (prepareSceneBody) while the scene keeps
  // running; addPreparedBodies adds the body when they are ready. False with errorMessage_ set
  // when the file cannot be read.
  bool addBodyFromMesh(const std::string& path);
  // Each frame, with the World quiescent: adds the bodies whose preparation finished, in the
  // order they were asked for (a failed one sets errorMessage_).
  void addPreparedBodies();
  void removeBody(int body);
  void duplicateBody(int body);  // the body as saved, lifted above the highest body
  void bodiesChanged();          // rebuilds what the viewer keeps per body

  // ---- viewer_params.cpp ----
  // The parameters every body has now become "the file's" (the scene was opened or saved).
  void rememberFileParams();
  const BodyParams* fileParamsOf(BodyHandle body) const;  // null: the body is not in the file
  // A panel control of `body` starts an edit: `before` is what Ctrl+Z brings back.
  void rememberParamEdit(BodyHandle body, const BodyParams& before);
  void setBodyParams(BodyHandle body, const BodyParams& params);  // errors to errorMessage_
  void undoParamEdit();                                           // Ctrl+Z
  void resetParamsToFile(BodyHandle body);                        // undoable

  // ---- viewer_plots.cpp ----
  void clearPlots();
  void samplePlots();  // once per frame that stepped
  void drawPlotsPanel();
  void drawBodyKineticPlot(int body);

  // ---- viewer_input.cpp ----
  void installCallbacks();
  void onMouseButton(int button, int action, int mods);
  void onCursorPos(double x, double y);
  void onScroll(double dx, double dy);
  void onKey(int key, int action, int mods);
  void beginDrag(double x, double y, bool nearestParticle);
  void updateDragTarget();
  void endDrag();
  render::Ray rayAtCursor(double x, double y) const;
  // The 3D view: the window right of the panel (window pixels, origin top left).
  struct ViewRect {
    float x = 0, y = 0, width = 1, height = 1;
  };
  ViewRect viewRect() const;
  // Window pixel of a world point; false when behind the eye.
  bool projectToWindow(const glm::vec3& point, glm::vec2* pixel) const;

  // ---- viewer_ui.cpp ----
  void drawUi();
  void drawPanel();
  void drawStatusBar();
  void drawQuitDialog();
  void drawBodyPanel(int body);
  void drawWorldPanel();
  void drawTimingPanel();
  void drawScenePanel();

  // ---- viewer_embedding.cpp ----
  // The body's embedding combo and option sliders (cage bodies with a render mesh).
  void drawEmbeddingControls(int body);
  void syncEmbeddingEdits(int body);  // the edit values from the body's method
  // Binds a pending switch (a frame after it was asked for, so the panel showed "binding...").
  void applyEmbeddingRequest();

  // ---- viewer_folds.cpp ----
  // The toggle (on the panel's time line), a folded body's warning on its name's line, and the
  // folded bodies in the status bar: warnings never push the panel's controls down.
  void drawFoldControls();
  void drawBodyFoldWarning(int body);
  void drawFoldStatus();
  bool foldStatusShown() const;  // drawFoldStatus draws something
  // Every kFoldCheckEvery frames while on: checks each watched body and recomputes the tint.
  // Returns whether it checked this frame.
  bool updateFoldCheck();
  void clearFolds();  // forgets the watch (bodies changed) and the tint
  void updateFoldTint(int body, const FoldWatch::FoldedRegion* region);
  void drawFoldTint();  // in renderFrame, after the bodies

  // ---- viewer_stats.cpp ----
  // Gathers the stats and hands them to statsWriter_, which writes options_.statsPath on its own
  // thread. Returns false when a write has failed so far (the reason went to stderr).
  // Not const: it keeps each body's grab triangle for the next write (BodyView::grabTriangle).
  bool writeStats();
  // writeStats(), its wall time on this thread added to statsMsSum_ (printed at exit).
  bool timedStatsWrite();

  ViewerOptions options_;
  Scene scene_;
  GLFWwindow* window_ = nullptr;
  bool imguiReady_ = false;
  int framebufferWidth_ = 0, framebufferHeight_ = 0;
  int windowWidth_ = 0, windowHeight_ = 0;

  std::unique_ptr<render::MeshRenderer> meshRenderer_;
  std::unique_ptr<render::GroundRenderer> groundRenderer_;
  std::unique_ptr<render::DebugDraw> debugDraw_;    // colliders, depth tested, 1-px points
  std::unique_ptr<render::DebugDraw> overlayDraw_;  // particles, cage, clusters, goals, drag
  float frameGroundHeight_ = 0.0f;                  // groundHeight() when the frame was queued
  // views_ hold the World's current positions, deformed (set by updateMeshes). Cleared by
  // whatever moves particles or changes bodies or bindings: a step, reset, rebuilt views, a
  // re-bind. A paused viewer then deforms nothing.
  bool meshesCurrent_ = false;
  std::vector<BodyView> views_;
  // Bodies from mesh files being prepared on another thread (addBodyFromMesh), oldest first.
  struct PendingBody {
    std::string name;
    std::chrono::steady_clock::time_point start;
    std::future<PreparedBody> prepared;
  };
  std::deque<PendingBody> pendingBodies_;
  render::OrbitCamera camera_;
  glm::vec3 panelColour_{0.06f};  // background of the ImGui panel (cleared, not drawn by ImGui)
  float sceneSize_ = 1.0f;  // diagonal of the bodies' bounds when the scene was opened, metres

  // Simulation control.
  bool paused_ = false;
  bool stepOnce_ = false;
  bool resetRequested_ = false;
  int stepsPerFrame_ = 1;
  bool panelHidden_ = false;  // key H: the 3D view takes the whole window

  // Overlays.
  bool showParticles_ = false;
  bool showCage_ = false;
  bool showClusters_ = false;
  bool showGoals_ = false;
  bool showColliders_ = true;
  bool cullBackFaces_ = true;

  // Mouse state.
  double cursorX_ = 0, cursorY_ = 0;
  bool orbiting_ = false, panning_ = false;

  // The active drag (left mouse button on a body).
  struct Drag {
    bool active = false;
    int id = -1;
    int body = -1;
    glm::vec3 planePoint{0.0f}, planeNormal{0.0f, 0.0f, 1.0f};
    glm::vec3 grabPoint{0.0f};  // where the body was grabbed (world)
    glm::vec3 target{0.0f};
    std::vector<int> particles;
    std::vector<double> weights;
    bool nearestParticle = false;
  } drag_;
  float dragStiffness_ = 0.2f;

  // Messages and events shown in the window.
  std::deque<std::string> eventLog_;
  long eventCount_ = 0;
  std::string errorMessage_, statusMessage_;
  std::string scenePathInput_, savePathInput_, screenshotPathInput_, addMeshPathInput_;
  int removeRequest_ = -1, duplicateRequest_ = -1;  // body buttons, applied after the panel
  bool overwriteShipped_ = false;                   // Save may rewrite a shipped scene
  // sceneText(scene_, scene_.path) when the scene was opened or last saved.
  std::string savedText_;
  // Body parameters: the file's (when opened or last saved) and the undo history of panel
  // edits, oldest first, at most kMaxParamUndo.
  struct ParamEdit {
    BodyHandle body;
    BodyParams before;
  };
  static constexpr std::size_t kMaxParamUndo = 200;
  std::vector<ParamEdit> fileParams_, paramUndo_;
  // Plots of the last 10 s (viewer_plots.cpp), one sample per frame that stepped.
  struct Plots {
    PlotHistory kinetic, linearMomentum, angularMomentum, contacts, deepestContact, stepMs;
    std::vector<PlotHistory> bodyKinetic;  // per body, in scene order
  } plots_;
  bool quitDialog_ = false;        // the "unsaved changes" dialog is open
  std::string screenshotRequest_;  // path of a screenshot to take after this frame is drawn
  // A --screenshot or --stats file could not be written: the program exits with code 1.
  bool outputFailed_ = false;
  long statsWrites_ = 0;
  double statsMsSum_ = 0.0;
  std::unique_ptr<StatsFileWriter> statsWriter_;  // with --stats

  // A switch of a body's embedding asked for in the panel, bound at the start of a later frame.
  struct EmbeddingRequest {
    int body = -1;  // -1: none
    cage::EmbeddingMethod method;
    long frame = 0;  // the frame it was asked in
  } embeddingRequest_;
  // The fold check (viewer_folds.cpp): on/off, the watch (made when first needed, in the
  // bodies' start pose), the folded bodies of the last check, and why the check stopped.
  bool foldCheck_ = false;
  std::unique_ptr<FoldWatch> foldWatch_;
  std::vector<FoldWatch::FoldedRegion> folds_;
  std::string foldError_;
  long lastFoldCheck_ = -1;

  FrameTimings timings_;
  // Window-pixel rectangles (x0, y0, x1, y1) of named panel controls in the last frame, written
  // to the stats file so tests can click them.
  std::map<std::string, std::array<float, 4>> widgetRects_;
  void recordWidget(const char* name);
  long frame_ = 0;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace sb::app
