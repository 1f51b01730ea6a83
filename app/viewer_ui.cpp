// The ImGui control panel: a fixed panel on the left of the window (fixed, so tests can click
// its controls at known pixels), and a status bar along the bottom of the 3D view for messages
// (errors, status, simulation events): messages never push the panel's controls down, so a
// control stays where the hand expects it. Every control has a tooltip. Changes apply
// immediately to the running World.
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "app/viewer_app.h"

namespace sb::app {

namespace {

void tooltip(const char* text) {
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", text);
}

// The double nearest the shortest decimal that reads back as v: a slider set to 0.05 stores
// 0.05, not 0.05000000074505806 (the float's exact value), so saved scenes read as typed.
double shortestDouble(float v) {
  char text[32];
  const std::to_chars_result r = std::to_chars(text, text + sizeof(text) - 1, v);
  *r.ptr = '\0';
  return std::strtod(text, nullptr);
}

// A float slider bound to a double, with a tooltip. Returns true when the value changed.
bool sliderDouble(const char* label, double* value, float lo, float hi, const char* format,
                  const char* help, ImGuiSliderFlags flags = 0) {
  float v = static_cast<float>(*value);
  const bool changed = ImGui::SliderFloat(label, &v, lo, hi, format, flags);
  tooltip(help);
  if (changed) *value = shortestDouble(v);
  return changed;
}

}  // namespace

void ViewerApp::recordWidget(const char* name) {
  const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
  widgetRects_[name] = {lo.x, lo.y, hi.x, hi.y};
}

void ViewerApp::drawUi() {
  widgetRects_.clear();
  if (!panelHidden_) drawPanel();
  drawStatusBar();
  drawQuitDialog();
}

void ViewerApp::drawQuitDialog() {
  const char* title = "Unsaved changes";
  if (quitDialog_ && !ImGui::IsPopupOpen(title)) ImGui::OpenPopup(title);
  if (!ImGui::BeginPopupModal(title, nullptr, ImGuiWindowFlags_AlwaysAutoResize)) return;
  ImGui::Text("The settings or parameters changed since the scene was opened or saved.");
  ImGui::Text("Save to: %s", savePathInput_.c_str());
  bool close = false;
  if (ImGui::Button("Save and quit")) {
    close = saveCurrentScene(savePathInput_);
    if (close) quit();
  }
  recordWidget("quitSave");
  ImGui::SameLine();
  if (ImGui::Button("Quit without saving")) {
    close = true;
    quit();
  }
  recordWidget("quitDiscard");
  ImGui::SameLine();
  if (ImGui::Button("Cancel")) close = true;
  recordWidget("quitCancel");
  if (!errorMessage_.empty())
    ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.35f, 1.0f), "%s", errorMessage_.c_str());
  if (close) {
    quitDialog_ = false;
    ImGui::CloseCurrentPopup();
  }
  ImGui::EndPopup();
}

void ViewerApp::drawPanel() {
  ImGui::SetNextWindowPos(ImVec2(0.0f, 0.0f), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, static_cast<float>(std::max(windowHeight_, 100))),
                           ImGuiCond_Always);
  ImGui::Begin("softbody", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::PushItemWidth(-140.0f);

  // ---- run control (first row: its position is fixed for the tests) ----
  ImGui::Checkbox("Pause", &paused_);
  recordWidget("pause");
  tooltip("Stop or resume the simulation (key: space). Dragging and the camera keep working.");
  ImGui::SameLine();
  if (ImGui::Button("Step")) {
    paused_ = true;
    stepOnce_ = true;
  }
  tooltip("Pause and advance exactly one time step (keys: S or N).");
  ImGui::SameLine();
  if (ImGui::Button("Reset")) resetRequested_ = true;
  tooltip("Put every body back to its start state; clears plastic deformation and drags (key: R).");
  ImGui::SameLine();
  // Taken after this frame is drawn (the back buffer holds nothing useful yet).
  if (ImGui::Button("Screenshot")) screenshotRequest_ = screenshotPathInput_;
  recordWidget("screenshot");
  tooltip("Write the current frame (with this panel) as a PNG to the path set under Scene file.");

  ImGui::Text("t = %.2f s   frame %ld   %.0f fps", scene_.world.time(), frame_,
              ImGui::GetIO().Framerate);
  ImGui::SameLine();
  drawFoldControls();  // on this line: a line more would push the body controls off the window

  const bool sceneOpen = ImGui::CollapsingHeader("Scene file");
  recordWidget("sceneHeader");
  if (sceneOpen) drawScenePanel();
  if (ImGui::CollapsingHeader("World", ImGuiTreeNodeFlags_DefaultOpen)) drawWorldPanel();
  if (ImGui::CollapsingHeader("Bodies", ImGuiTreeNodeFlags_DefaultOpen)) {
    for (std::size_t i = 0; i < scene_.bodies.size(); ++i) drawBodyPanel(static_cast<int>(i));
  }
  if (ImGui::CollapsingHeader("Overlays", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Checkbox("particles", &showParticles_);
    tooltip("Show the simulated particles (the cage vertices) as points (key: P).");
    ImGui::SameLine();
    ImGui::Checkbox("cage", &showCage_);
    tooltip("Show the particle mesh (cage) as a wireframe (key: C).");
    ImGui::SameLine();
    ImGui::Checkbox("clusters", &showClusters_);
    tooltip(
        "Show each shape-matching cluster in its own colour: lines from the cluster's centre "
        "to its particles (key: K).");
    ImGui::Checkbox("goals", &showGoals_);
    tooltip("Show the goal positions shape matching pulls the particles toward (key: G).");
    ImGui::SameLine();
    ImGui::Checkbox("colliders", &showColliders_);
    tooltip("Show static colliders other than the ground as wireframes.");
    ImGui::SameLine();
    ImGui::Checkbox("cull", &cullBackFaces_);
    tooltip(
        "Skip the back faces of the body meshes (faster). Turn off to see the inside of "
        "inverted or torn meshes.");
  }
  if (ImGui::CollapsingHeader("Timings", ImGuiTreeNodeFlags_DefaultOpen)) drawTimingPanel();
  const bool plotsOpen = ImGui::CollapsingHeader("Plots (last 10 s)");
  recordWidget("plotsHeader");
  tooltip("Kinetic energy, momenta, contacts, the deepest contact and the step time per frame.");
  if (plotsOpen) drawPlotsPanel();
  if (ImGui::CollapsingHeader("Help")) {
    ImGui::TextWrapped(
        "Left drag: pull the surface point under the cursor.\n"
        "Ctrl + left drag: pull the nearest particle.\n"
        "Right drag: orbit. Shift + right drag or middle drag: pan. Wheel: zoom.\n"
        "Space: pause. S/N: step. R: reset. F: frame the scene. H: hide/show this panel.\n"
        "Ctrl+Z: undo a parameter change. P/C/K/G: particles, cage, clusters, goals.\n"
        "Arrows: orbit. +/-: zoom. Esc/Q: quit.");
  }
  ImGui::PopItemWidth();
  ImGui::End();
}

void ViewerApp::drawStatusBar() {
  const ViewRect view = viewRect();
  // Across the bottom of the 3D view, as tall as its lines (at most half the view), in front of
  // the scene; it takes no focus, so the keys keep working.
  ImGui::SetNextWindowPos(ImVec2(view.x, view.y + view.height), ImGuiCond_Always,
                          ImVec2(0.0f, 1.0f));
  ImGui::SetNextWindowSizeConstraints(ImVec2(view.width, 0.0f),
                                      ImVec2(view.width, 0.5f * view.height));
  ImGui::SetNextWindowBgAlpha(0.8f);
  ImGui::Begin("##status", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize |
                   ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                   ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav);
  if (!errorMessage_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.4f, 0.35f, 1.0f));
    ImGui::TextWrapped("%s", errorMessage_.c_str());
    ImGui::PopStyleColor();
    if (ImGui::SmallButton("dismiss")) errorMessage_.clear();
    tooltip("Hide this message.");
  }
  if (!eventLog_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.85f, 0.3f, 1.0f));
    ImGui::TextWrapped("%ld simulation event(s); latest: %s", eventCount_,
                       eventLog_.front().c_str());
    ImGui::PopStyleColor();
    tooltip("Bodies whose state became NaN/Inf are reset to their start by the simulation.");
    if (ImGui::SmallButton("all events")) ImGui::OpenPopup("events");
    ImGui::SameLine();
    if (ImGui::SmallButton("clear")) eventLog_.clear();
    tooltip("Forget the listed events.");
    if (ImGui::BeginPopup("events")) {
      for (const std::string& e : eventLog_) ImGui::BulletText("%s", e.c_str());
      ImGui::EndPopup();
    }
  }
  drawFoldStatus();
  if (!statusMessage_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled));
    ImGui::TextWrapped("%s", statusMessage_.c_str());
    ImGui::PopStyleColor();
  } else if (errorMessage_.empty() && eventLog_.empty() && !foldStatusShown()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled));
    ImGui::TextWrapped(
        "Left drag: pull a body (Ctrl: one particle). Right drag: orbit. Wheel: zoom. "
        "H: hide the panel. All keys: Help, last in the panel.");
    ImGui::PopStyleColor();
  }
  ImGui::End();
}

void ViewerApp::drawWorldPanel() {
  World& world = scene_.world;
  WorldSettings s = world.settings();
  bool changed = false;
  float gravity[3] = {static_cast<float>(s.gravity.x()), static_cast<float>(s.gravity.y()),
                      static_cast<float>(s.gravity.z())};
  if (ImGui::DragFloat3("gravity", gravity, 0.05f, -50.0f, 50.0f, "%.2f")) {
    s.gravity =
        Vec3(shortestDouble(gravity[0]), shortestDouble(gravity[1]), shortestDouble(gravity[2]));
    changed = true;
  }
  tooltip("Gravity acceleration in m/s^2 (x, y, z). Drag a number or double-click to type.");
  double stepMs = s.timeStep * 1000.0;
  if (sliderDouble(
          "time step (ms)", &stepMs, 1.0f, 50.0f, "%.2f",
          "Simulated time advanced per frame, milliseconds. One step runs per drawn frame, "
          "so 16.67 ms at 60 fps is real time.",
          ImGuiSliderFlags_Logarithmic)) {
    s.timeStep = stepMs / 1000.0;
    changed = true;
  }
  if (ImGui::SliderInt("substeps", &s.substeps, 1, 20)) changed = true;
  tooltip("Sub-steps per time step: more = stiffer contacts and goals, more cost.");
  double maxSubstepMs = s.maxSubstep * 1000.0;
  if (sliderDouble("max sub-step (ms)", &maxSubstepMs, 1.0f, 1000.0f, "%.2f",
                   "Longest sub-step: a time step longer than substeps x this runs more\n"
                   "sub-steps. Contacts need short sub-steps (default 8.33 ms); the\n"
                   "material is the same at any sub-step. Range 1 ms to 1 s.",
                   ImGuiSliderFlags_Logarithmic)) {
    s.maxSubstep = maxSubstepMs / 1000.0;
    changed = true;
  }
  if (ImGui::Checkbox("bodies collide", &s.bodyContact)) changed = true;
  tooltip("Body-body contact: particles are kept out of the other bodies' cages.");
  if (sliderDouble("body friction", &s.contactFriction, 0.0f, 2.0f, "%.2f",
                   "Friction coefficient mu between bodies."))
    changed = true;
  if (sliderDouble("rolling resistance", &s.rollingResistance, 0.0f, 0.3f, "%.3f",
                   "Couple against rolling and rocking, as a share of each body's radius\n"
                   "times the contact force (0: none). A ball stays put on slopes below\n"
                   "about atan of it; bodies rocking on a rounded part come to rest sooner."))
    changed = true;
  if (ImGui::Checkbox("sleep", &s.sleep)) changed = true;
  tooltip(
      "Bodies at rest fall asleep and skip the step until something wakes them\n"
      "(a touch by an awake body, a drag, a parameter change).");
  if (changed) {
    try {
      world.setSettings(s);
    } catch (const std::exception& e) {
      errorMessage_ = e.what();
    }
  }

  const std::vector<Collider>& colliders = world.colliders();
  if (!colliders.empty()) {
    double friction = colliders.front().friction;
    if (sliderDouble("friction", &friction, 0.0f, 2.0f, "%.2f",
                     "Friction coefficient mu of every collider (ground included).")) {
      std::vector<Collider> updated = colliders;
      try {
        world.clearColliders();
        for (Collider& c : updated) {
          c.friction = friction;
          world.addCollider(c);
        }
      } catch (const std::exception& e) {
        errorMessage_ = e.what();
      }
    }
  } else {
    ImGui::TextDisabled("no colliders");
  }
  if (ImGui::SliderFloat("drag stiffness", &dragStiffness_, 0.01f, 1.0f, "%.2f")) {
    if (drag_.active) scene_.world.setDragStiffness(drag_.id, dragStiffness_);
  }
  tooltip(
      "Fraction of the gap between the grabbed point and the mouse closed per step "
      "(mouse dragging).");
}

void ViewerApp::drawBodyPanel(int body) {
  World& world = scene_.world;
  const BodyHandle h = scene_.bodies[body].handle;
  const BodyView& v = views_[body];
  ImGui::PushID(body);
  ImGui::ColorButton("##colour", ImVec4(v.colour.r, v.colour.g, v.colour.b, 1.0f),
                     ImGuiColorEditFlags_NoTooltip, ImVec2(12, 12));
  ImGui::SameLine();
  const bool open =
      ImGui::TreeNodeEx(world.name(h).c_str(), body == 0 ? ImGuiTreeNodeFlags_DefaultOpen : 0);
  tooltip("Parameters of this body (its colour in the view on the left).");
  drawBodyFoldWarning(body);
  if (open) {
    const BodyParams before = world.params(h);
    BodyParams p = before;
    bool changed = false;
    bool editStarted = false;  // a control of this body was clicked or grabbed this frame
    int mode = static_cast<int>(p.mode);
    if (ImGui::Combo("mode", &mode, "rigid\0linear\0quadratic\0")) {
      p.mode = static_cast<Mode>(mode);
      changed = true;
      editStarted = true;
    }
    tooltip(
        "Shape matching goal: rigid keeps the rest shape; linear allows shear and stretch; "
        "quadratic also bending and twisting.");
    // The first body's sliders are recorded for the tests (they click and compare positions).
    auto record = [&](const char* name) {
      if (body == 0) recordWidget(name);
    };
    // After every control: an edit that starts is remembered for Ctrl+Z, once per drag.
    auto track = [&] { editStarted = editStarted || ImGui::IsItemActivated(); };
    changed |=
        sliderDouble("alpha", &p.alpha, 0.0f, 1.0f, "%.3f",
                     "Stiffness, [0, 1]: share of the way to the goal per 1/240 s (1 = onto the\n"
                     "goal: rigid in rigid mode). The same material at any number of clusters\n"
                     "and any time step or sub-step count.");
    track();
    record("alpha");
    changed |= sliderDouble(
        "beta", &p.beta, 0.0f, 1.0f, "%.3f",
        "Blend, [0, 1], of the goal between rotation only (0) and the linear/quadratic fit (1),\n"
        "applied as 0.9 x beta so every shape keeps a restoring force (at 1/240 s;\n"
        "converted for other sub-steps so the material stays the same).");
    track();
    record("beta");
    changed |=
        sliderDouble("damping", &p.damping, 0.0f, 1.0f, "%.3f",
                     "Damping, [0, 1]: share of the velocity relative to the body's rigid motion\n"
                     "removed per 1/240 s, the same per second at any sub-step (pinned\n"
                     "bodies: the motion their pins allow, so a swing comes to rest).");
    track();
    changed |=
        sliderDouble("restitution", &p.restitution, 0.0f, 1.0f, "%.2f",
                     "Restitution, [0, 1]: share of the approach speed an impact gives back\n"
                     "(0 = no bounce); a contact uses the larger of its two sides'. Impacts\n"
                     "faster than the threshold (1 m/s) rebound e^2 of the fall height, soft\n"
                     "bodies too (their impact is one event of the two bodies as a whole).");
    track();
    changed |= sliderDouble("c_yield", &p.plasticity.yield, 0.0f, 1.0f, "%.3f",
                            "Plastic yield, >= 0 (slider 0 to 1): stretch ||S - I|| above which\n"
                            "the rest shape creeps.");
    track();
    record("c_yield");
    changed |= sliderDouble("c_creep", &p.plasticity.creep, 0.0f, 20.0f, "%.2f",
                            "Plastic creep rate in 1/s, >= 0 (slider 0 to 20; 0 = no plasticity):\n"
                            "a sub-step of h seconds absorbs 1 - exp(-h creep) of the stretch\n"
                            "beyond the yield.");
    track();
    record("c_creep");
    changed |= sliderDouble("c_max", &p.plasticity.max, 0.0f, 2.0f, "%.3f",
                            "Upper bound of the permanent deformation ||Sp - I||, [0, 2].");
    track();
    if (editStarted) rememberParamEdit(h, before);
    if (changed) setBodyParams(h, p);
    const BodyParams* file = fileParamsOf(h);
    if (ImGui::SmallButton("reset parameters") && file) resetParamsToFile(h);
    if (body == 0) recordWidget("resetParams");
    tooltip(file ? "Set this body's parameters back to the scene file's (as opened or last\n"
                   "saved). Ctrl+Z undoes parameter changes one at a time."
                 : "This body is not in the scene file (added here): nothing to reset to.\n"
                   "Ctrl+Z undoes parameter changes one at a time.");

    // Clusters: rebuilt when a control is released (a rebuild clears plastic deformation).
    ClusterDef clusters = world.clusterDef(h);
    bool rebuild = false;
    int kind = clusters.kind == ClusterDef::Kind::Grid ? 1 : 0;
    if (clusters.kind == ClusterDef::Kind::Explicit) {
      ImGui::TextDisabled("clusters: explicit lists from the scene");
      if (ImGui::SmallButton("use a grid instead")) {
        clusters.kind = ClusterDef::Kind::Grid;
        rebuild = true;
      }
      tooltip("Replace the scene's explicit clusters with a grid of cells.");
    } else {
      if (ImGui::RadioButton("single cluster", &kind, 0)) rebuild = true;
      tooltip("One cluster with every particle: the body deforms only as a whole.");
      ImGui::SameLine();
      if (ImGui::RadioButton("grid", &kind, 1)) rebuild = true;
      tooltip(
          "Overlapping cubic cells over the rest shape: smaller cells = finer local detail\n"
          "(the stiffness is alpha's and beta's at any number of clusters).");
      clusters.kind = kind == 1 ? ClusterDef::Kind::Grid : ClusterDef::Kind::Single;
    }
    const glm::vec3 extent = v.boundsMax - v.boundsMin;
    const float size = std::max({extent.x, extent.y, extent.z, 1e-3f});
    if (clusters.kind == ClusterDef::Kind::Grid) {
      float cell = static_cast<float>(clusters.cellSize);
      ImGui::SliderFloat("cell size (m)", &cell, size / 20.0f, size * 1.5f, "%.3f",
                         ImGuiSliderFlags_Logarithmic);
      if (ImGui::IsItemDeactivatedAfterEdit()) rebuild = true;
      tooltip("Edge of a grid cell in metres; applied when you release the slider.");
      clusters.cellSize = shortestDouble(cell);
      float overlap = static_cast<float>(clusters.overlap);
      ImGui::SliderFloat("overlap (m)", &overlap, 0.0f, size * 0.5f, "%.3f");
      if (ImGui::IsItemDeactivatedAfterEdit()) rebuild = true;
      tooltip(
          "Each cell also takes particles within this distance: couples neighbouring "
          "clusters. Applied when you release the slider.");
      clusters.overlap = shortestDouble(overlap);
    }
    if (rebuild) {
      try {
        world.setClusters(h, clusters);
        refreshClusters(body);
      } catch (const std::exception& e) {
        errorMessage_ = world.name(h) + ": " + e.what();
      }
    }
    ImGui::Text("%d particles, %d clusters", world.particleCount(h), world.clusterCount(h));
    drawEmbeddingControls(body);
    drawBodyKineticPlot(body);
    if (ImGui::SmallButton("duplicate")) duplicateRequest_ = body;
    recordWidget(("duplicate" + std::to_string(body)).c_str());
    tooltip("Add a copy of this body (as it would be saved) above the scene.");
    ImGui::SameLine();
    if (ImGui::SmallButton("remove")) removeRequest_ = body;
    recordWidget(("remove" + std::to_string(body)).c_str());
    tooltip("Remove this body from the scene.");
    ImGui::TreePop();
  }
  ImGui::PopID();
}

void ViewerApp::drawTimingPanel() {
  const StepProfile& p = scene_.world.lastProfile();
  const double ms = 1000.0;
  ImGui::Text("simulation %.3f ms  (last step() %.3f ms)", timings_.lastSim, p.total() * ms);
  tooltip("Wall time of this frame's World::step() calls, and the phases of the last one.");
  // Every phase of the step, two to a line.
  for (int i = 0; i < kPhaseCount; i += 2) {
    const Phase a = kPhases[size_t(i)];
    if (i + 1 < kPhaseCount) {
      const Phase b = kPhases[size_t(i) + 1];
      ImGui::Text("  %-10s %.3f  %-10s %.3f", phaseName(a), p[a] * ms, phaseName(b), p[b] * ms);
    } else {
      ImGui::Text("  %-10s %.3f", phaseName(a), p[a] * ms);
    }
  }
  ImGui::Text("  body-body contacts: %d", scene_.world.lastContactCount());
  ImGui::Text("deform %.3f ms   render %.3f ms", timings_.lastDeform, timings_.lastRender);
  tooltip(
      "deform: render vertices = W x particles, plus smooth normals.\n"
      "render: panel, drawing, buffer swap.");
  ImGui::Text("frame %.2f ms", timings_.lastFrame);
  int cap = static_cast<int>(options_.fpsCap + 0.5);
  if (ImGui::SliderInt("fps cap", &cap, 0, 240, cap == 0 ? "uncapped" : "%d fps"))
    options_.fpsCap = cap;
  tooltip(
      "Frames per second at most (0 = as fast as possible). One simulation step runs per "
      "frame. Vsync does not limit the rate under Xvfb, this cap does.");
  const int n = FrameTimings::kHistory;
  const ImVec2 plotSize(kPanelWidth - 140.0f, 36.0f);
  ImGui::PlotLines("simulation", timings_.simHistory.data(), n, timings_.cursor, nullptr, 0.0f,
                   FLT_MAX, plotSize);
  tooltip("Simulation milliseconds per frame, last 3 seconds.");
  ImGui::PlotLines("deform", timings_.deformHistory.data(), n, timings_.cursor, nullptr, 0.0f,
                   FLT_MAX, plotSize);
  tooltip("Deformation (W x particles) and normals, milliseconds per frame.");
  ImGui::PlotLines("render", timings_.renderHistory.data(), n, timings_.cursor, nullptr, 0.0f,
                   FLT_MAX, plotSize);
  tooltip("Panel, drawing and swap, milliseconds per frame.");
  ImGui::PlotLines("frame", timings_.frameHistory.data(), n, timings_.cursor, nullptr, 0.0f,
                   FLT_MAX, plotSize);
  tooltip("Time between frames in milliseconds (the frame cap makes it 16.7 ms at 60 fps).");
}

void ViewerApp::drawScenePanel() {
  ImGui::InputText("scene file", &scenePathInput_);
  recordWidget("scenePath");
  tooltip("Path of a scene JSON file to open.");
  if (ImGui::Button("Open")) openScene(scenePathInput_);
  recordWidget("open");
  tooltip(
      "Open the scene file above. If it has an error, the message shows here and the "
      "current scene keeps running.");
  ImGui::InputText("save as", &savePathInput_);
  recordWidget("savePath");
  tooltip("Path to save the current scene with its current parameters to.");
  if (ImGui::Button("Save")) saveCurrentScene(savePathInput_);
  recordWidget("save");
  tooltip(
      "Write the scene with the current world settings and body parameters "
      "(atomic: a temporary file renamed over the target).");
  ImGui::SameLine();
  ImGui::Checkbox("overwrite shipped scenes", &overwriteShipped_);
  tooltip(
      "The scenes that come with softbody are read-only here (Save proposes NAME-edited.json\n"
      "in the current folder instead); tick to let Save rewrite them.");
  ImGui::InputText("add mesh", &addMeshPathInput_);
  recordWidget("addMeshPath");
  tooltip(
      "A mesh file (OBJ, OFF, PLY, STL) to add as a soft body with an automatic cage.\n"
      "Dropping a mesh file on the window does the same.");
  if (ImGui::Button("Add body")) addBodyFromMesh(addMeshPathInput_);
  recordWidget("addMesh");
  tooltip("Add the mesh above as a body (linear, alpha 0.5), sized and placed above the scene.");
  ImGui::InputText("screenshot", &screenshotPathInput_);
  tooltip("PNG path the Screenshot button writes to.");
}

}  // namespace sb::app
