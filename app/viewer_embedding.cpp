// Switching a body's embedding live (issue 14, item 8): a combo per body offers the methods a
// scene accepts for a cage body, with their options (harmonic grid resolution, RBF shape). A
// switch re-binds the render mesh through the scene library (sim/scene/body_embedding.h), which
// replaces the old binding only when the new one is complete, so a refused method leaves the
// body as it was and the panel says why.
//
// The bind runs on the frame thread: a harmonic bind takes ~0.5 s at resolution 32 (~5 s at 64),
// and a worker thread would have to keep the World and the Scene's bodies from changing under
// it (drops, removals, a scene opened). Instead the request waits one frame, so the panel has
// shown "binding ..." on screen before the frame thread blocks for it.
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

#include <imgui.h>

#include "app/viewer_app.h"
#include "sim/scene/body_embedding.h"

namespace sb::app {

namespace {

// The methods a scene offers for a cage body, in the combo's order. A refused bind (Green
// coordinates for a render mesh that sticks out of its cage, an option out of range) is shown
// and the old binding kept.
constexpr cage::EmbeddingKind kCageMethods[] = {
    cage::EmbeddingKind::MeanValue, cage::EmbeddingKind::Harmonic, cage::EmbeddingKind::Rbf,
    cage::EmbeddingKind::Green};

const char* methodHelp(cage::EmbeddingKind kind) {
  switch (kind) {
    case cage::EmbeddingKind::MeanValue:
      return "Mean value coordinates: smooth, exact on the cage; weights may be negative in\n"
             "concave parts. Binds in tens of milliseconds.";
    case cage::EmbeddingKind::Harmonic:
      return "Harmonic coordinates: a Laplace solve on a grid inside the cage; weights >= 0 and\n"
             "local to the interior. Binds in ~0.5 s at resolution 32, ~5 s at 64.";
    case cage::EmbeddingKind::Rbf:
      return "Multiquadric RBF interpolation of the cage vertices' motion: smooth, global,\n"
             "reproduces affine motion.";
    case cage::EmbeddingKind::Green:
      return "Green coordinates: shape-preserving (similarities exactly), driven by the cage's\n"
             "vertices and face normals.";
    default:
      return "";
  }
}

// "harmonic (resolution 32)", "rbf (shape 1)", "mvc".
std::string describe(const cage::EmbeddingMethod& m) {
  std::string text = cage::embeddingKindName(m.kind);
  char options[64] = "";
  if (m.kind == cage::EmbeddingKind::Harmonic)
    std::snprintf(options, sizeof options, " (resolution %d)", m.harmonic.resolution);
  if (m.kind == cage::EmbeddingKind::Rbf)
    std::snprintf(options, sizeof options, " (shape %g)", m.rbf.shape);
  return text + options;
}

// The double nearest the shortest decimal that reads back as v (a slider at 2.3 gives 2.3, not
// 2.2999999523: the shape is saved with the scene).
double shortestDouble(float v) {
  char text[32];
  const std::to_chars_result r = std::to_chars(text, text + sizeof(text) - 1, v);
  *r.ptr = '\0';
  return std::strtod(text, nullptr);
}

}  // namespace

void ViewerApp::syncEmbeddingEdits(int body) {
  const cage::EmbeddingMethod& m = scene_.bodies[static_cast<std::size_t>(body)].embedding;
  BodyView& v = views_[static_cast<std::size_t>(body)];
  v.editResolution = m.kind == cage::EmbeddingKind::Harmonic ? m.harmonic.resolution
                                                             : cage::HarmonicOptions{}.resolution;
  v.editShape = static_cast<float>(m.kind == cage::EmbeddingKind::Rbf ? m.rbf.shape
                                                                      : cage::RbfOptions{}.shape);
}

void ViewerApp::drawEmbeddingControls(int body) {
  const SceneBody& b = scene_.bodies[static_cast<std::size_t>(body)];
  BodyView& v = views_[static_cast<std::size_t>(body)];
  const std::string id = std::to_string(body);
  if (!b.render) return;  // nothing to embed: the body draws its particles
  if (b.latticeFrame) {
    ImGui::TextDisabled(
        "embedding: %s lattice (its nodes are the particles)",
        b.lattice && b.lattice->basis == cage::FfdBasis::BSpline ? "B-spline" : "Bernstein");
    return;
  }
  const bool pending = embeddingRequest_.body == body;
  const cage::EmbeddingMethod current = b.embedding;
  cage::EmbeddingMethod wanted = current;
  bool request = false;
  ImGui::BeginDisabled(pending);
  if (ImGui::BeginCombo("embedding", cage::embeddingKindName(current.kind))) {
    for (const cage::EmbeddingKind kind : kCageMethods) {
      if (ImGui::Selectable(cage::embeddingKindName(kind), kind == current.kind) &&
          kind != current.kind) {
        wanted.kind = kind;
        wanted.harmonic.resolution = v.editResolution;
        wanted.rbf.shape = shortestDouble(v.editShape);
        request = true;
      }
      recordWidget(("embedding" + id + "." + cage::embeddingKindName(kind)).c_str());
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", methodHelp(kind));
    }
    ImGui::EndCombo();
  }
  recordWidget(("embedding" + id).c_str());
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "How the render mesh follows the cage. Choosing another method binds the mesh again\n"
        "(the old binding stays until the new one is complete, and if it is refused).");
  // The options of the current method; applied when the slider is released or a typed value
  // entered. Typed values are not clamped: the cage library checks them and says why it refuses.
  if (current.kind == cage::EmbeddingKind::Harmonic) {
    ImGui::SliderInt("resolution", &v.editResolution, 4, 64);
    recordWidget(("resolution" + id).c_str());
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "Grid cells across the cage's longest side, [4, 64]: finer = closer to the exact\n"
          "harmonic coordinates, slower to bind (~0.5 s at 32, ~5 s at 64). Applied on release.");
    if (ImGui::IsItemDeactivatedAfterEdit() && v.editResolution != current.harmonic.resolution) {
      wanted.harmonic.resolution = v.editResolution;
      request = true;
    }
  } else if (current.kind == cage::EmbeddingKind::Rbf) {
    ImGui::SliderFloat("shape", &v.editShape, 0.0f, 10.0f, "%.2f");
    recordWidget(("shape" + id).c_str());
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "Multiquadric shape, [0, 10], in mean nearest-handle distances: 0 = creased at the\n"
          "handles, larger = smoother and worse conditioned. Applied on release.");
    if (ImGui::IsItemDeactivatedAfterEdit() && shortestDouble(v.editShape) != current.rbf.shape) {
      wanted.rbf.shape = shortestDouble(v.editShape);
      request = true;
    }
  }
  ImGui::EndDisabled();
  if (request && !pending) {
    embeddingRequest_.body = body;
    embeddingRequest_.method = wanted;
    embeddingRequest_.frame = frame_;
    v.embeddingError.clear();
  }
  if (embeddingRequest_.body == body) {
    ImGui::TextColored(ImVec4(1.0f, 0.85f, 0.3f, 1.0f), "binding %s ...",
                       describe(embeddingRequest_.method).c_str());
  } else if (!v.embeddingError.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.4f, 0.35f, 1.0f));
    ImGui::TextWrapped("%s", v.embeddingError.c_str());
    ImGui::PopStyleColor();
    // A new refusal is brought into view: the body's controls often end below the window.
    if (std::exchange(v.showEmbeddingError, false)) ImGui::SetScrollHereY(1.0f);
    recordWidget(("embeddingError" + id).c_str());
  }
}

void ViewerApp::applyEmbeddingRequest() {
  const EmbeddingRequest r = embeddingRequest_;
  embeddingRequest_ = EmbeddingRequest{};
  if (r.body < 0 || r.body >= static_cast<int>(scene_.bodies.size())) return;
  const std::string name =
      scene_.world.name(scene_.bodies[static_cast<std::size_t>(r.body)].handle);
  const cage::EmbeddingMethod old = scene_.bodies[static_cast<std::size_t>(r.body)].embedding;
  BodyView& v = views_[static_cast<std::size_t>(r.body)];
  bool switched = false;
  try {
    const auto start = std::chrono::steady_clock::now();
    rebindRenderMesh(scene_, r.body, r.method);
    meshesCurrent_ = false;  // the vertices follow the new weights from the next frame on
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!v.embeddingError.empty() && errorMessage_ == name + ": " + v.embeddingError)
      errorMessage_.clear();  // this body's earlier refusal no longer holds
    v.embeddingError.clear();
    v.currentWhileAsleep = false;  // a sleeping body's vertices must follow the new weights
    char text[256];
    std::snprintf(text, sizeof text, "%s: render mesh bound with %s in %.2f s", name.c_str(),
                  describe(r.method).c_str(), seconds);
    statusMessage_ = text;
    std::printf("softbody: %s\n", text);
    switched = true;
  } catch (const std::exception& e) {
    // The reason without the body's name where the scene library put it first: the panel shows
    // it under the body's own controls, the status bar adds the name once.
    std::string reason = e.what();
    if (reason.rfind(name + ": ", 0) == 0) reason.erase(0, name.size() + 2);
    v.embeddingError =
        "cannot bind with " + describe(r.method) + ": " + reason + " (kept " + describe(old) + ")";
    v.showEmbeddingError = true;
    std::fprintf(stderr, "softbody: %s: %s\n", name.c_str(), v.embeddingError.c_str());
    // Also in the status bar, which no longer reports the earlier switch as the latest news.
    errorMessage_ = name + ": " + v.embeddingError;
    statusMessage_.clear();
  }
  syncEmbeddingEdits(r.body);
  // The fold watch samples the map with the body's method: watch this body again with its new
  // one (a refused switch kept the old method, and the watch with it).
  if (switched && foldWatch_) {
    try {
      foldWatch_->rewatch(scene_, r.body);
    } catch (const std::exception& e) {
      foldError_ = name + ": cannot watch the new embedding for folds: " + e.what();
      foldWatch_.reset();
      folds_.clear();
    }
  }
  lastFoldCheck_ = -1;  // check again now
}

}  // namespace sb::app
