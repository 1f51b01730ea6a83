// The fold check in the viewer (issue 14, item 6): while "fold check" is ticked, every few
// frames each body with a render mesh has its map checked for folds (det J <= 0 at samples inside
// its cage or lattice: sim/scene/fold_watch.h), the panel names each folded body with its
// number of folded samples, and the render mesh is tinted where it folds.
//
// What is tinted: the render vertices within one sample spacing of a folded sample, both where
// they are now (the sample's deformed position). The samples are what the check measured, so
// the tint shows exactly the evidence of the warning, at the cost of one deform of the probes per
// folded body (which the check does anyway) and a distance test per vertex and folded sample.
// det J evaluated at the mesh vertices themselves was the alternative: it needs four more rows
// per vertex bound with the body's method (a second harmonic solve per switch, 4x the render
// mesh's weights in memory) and a deform of all of them every check, and a vertex on the cage
// boundary has offsets outside the cage, where harmonic weights are not defined.
#include <algorithm>
#include <cstdio>
#include <string>

#include <imgui.h>

#include "app/viewer_app.h"
#include "render/gl.h"
#include "render/mesh_buffer.h"
#include "render/mesh_renderer.h"

namespace sb::app {

namespace {

constexpr int kFoldCheckEvery = 5;  // frames between checks (a check is ~1 ms per body)
const glm::vec4 kFoldColour(1.0f, 0.1f, 0.85f, 0.85f);  // magenta: no body colour is near it

}  // namespace

void ViewerApp::drawFoldControls() {
  if (ImGui::Checkbox("folds", &foldCheck_)) {
    // Off: the watch goes too (no rebinding its samples on a switch); on: made afresh.
    clearFolds();
    if (!foldCheck_)
      for (std::size_t i = 0; i < views_.size(); ++i) updateFoldTint(static_cast<int>(i), nullptr);
  }
  recordWidget("foldCheck");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "Fold check: every %d frames, whether a body's render mesh passes through itself\n"
        "(det J <= 0 at samples inside its cage or lattice, relative to its start). Folded\n"
        "bodies are named in the bar below the view and on their line in Bodies; their folded\n"
        "regions are tinted magenta.",
        kFoldCheckEvery);
}

bool ViewerApp::foldStatusShown() const {
  return foldCheck_ && (!folds_.empty() || !foldError_.empty());
}

void ViewerApp::drawFoldStatus() {
  if (!foldCheck_) return;
  if (!foldError_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.4f, 0.35f, 1.0f));
    ImGui::TextWrapped("%s", foldError_.c_str());
    ImGui::PopStyleColor();
    return;
  }
  for (const FoldWatch::FoldedRegion& f : folds_) {
    const std::string name =
        scene_.world.name(scene_.bodies[static_cast<std::size_t>(f.body)].handle);
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.35f, 0.85f, 1.0f));
    ImGui::TextWrapped("FOLD: %s: %d of %d samples folded (smallest det J %.3f)", name.c_str(),
                       f.report.folded, f.report.samples, f.report.minDeterminant);
    ImGui::PopStyleColor();
    recordWidget(("foldStatus" + std::to_string(f.body)).c_str());
  }
}

void ViewerApp::drawBodyFoldWarning(int body) {
  for (const FoldWatch::FoldedRegion& f : folds_) {
    if (f.body != body) continue;
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.85f, 1.0f), "FOLDED %d/%d", f.report.folded,
                       f.report.samples);
    recordWidget(("foldWarning" + std::to_string(body)).c_str());
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "%d of %d samples inside this body's cage have det J <= 0 (smallest %.3f): the\n"
          "render mesh passes through itself there (tinted magenta).",
          f.report.folded, f.report.samples, f.report.minDeterminant);
  }
}

void ViewerApp::clearFolds() {
  foldWatch_.reset();
  folds_.clear();
  foldError_.clear();
  lastFoldCheck_ = -1;
}

bool ViewerApp::updateFoldCheck() {
  if (!foldCheck_ || !foldError_.empty()) return false;
  if (lastFoldCheck_ >= 0 && frame_ - lastFoldCheck_ < kFoldCheckEvery) return false;
  lastFoldCheck_ = frame_;
  try {
    // In the start pose, so the watch means the same whenever it is made (the check may be
    // ticked while a body is dragged out of shape).
    if (!foldWatch_) foldWatch_ = std::make_unique<FoldWatch>(scene_, 500, FoldWatch::Pose::Start);
    folds_ = foldWatch_->foldedRegions(scene_);
  } catch (const std::exception& e) {
    foldError_ = std::string("fold check stopped: ") + e.what();
    foldWatch_.reset();
    folds_.clear();
  }
  std::vector<const FoldWatch::FoldedRegion*> byBody(views_.size(), nullptr);
  for (const FoldWatch::FoldedRegion& f : folds_)
    if (f.body >= 0 && f.body < static_cast<int>(byBody.size()))
      byBody[static_cast<std::size_t>(f.body)] = &f;
  for (std::size_t i = 0; i < views_.size(); ++i) updateFoldTint(static_cast<int>(i), byBody[i]);
  return true;
}

void ViewerApp::updateFoldTint(int body, const FoldWatch::FoldedRegion* region) {
  BodyView& v = views_[static_cast<std::size_t>(body)];
  v.tintTriangles.clear();
  v.tintedVertices = 0;
  v.tintUploaded = false;
  if (!region || region->points.empty()) return;
  const auto n = static_cast<std::size_t>(v.vertices.rows());
  std::vector<char> near(n, 0);
  const float radius = static_cast<float>(region->spacing);
  const float radius2 = radius * radius;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3f x = v.vertices.row(static_cast<Eigen::Index>(k)).transpose();
    for (const Vec3& p : region->points)
      if ((x - p.cast<float>()).squaredNorm() <= radius2) {
        near[k] = 1;
        ++v.tintedVertices;
        break;
      }
  }
  for (std::size_t t = 0; t + 2 < v.triangles.size(); t += 3)
    if (near[static_cast<std::size_t>(v.triangles[t])] ||
        near[static_cast<std::size_t>(v.triangles[t + 1])] ||
        near[static_cast<std::size_t>(v.triangles[t + 2])])
      v.tintTriangles.insert(v.tintTriangles.end(), v.triangles.begin() + static_cast<long>(t),
                             v.triangles.begin() + static_cast<long>(t) + 3);
}

void ViewerApp::drawFoldTint() {
  if (options_.hideBodies) return;
  // The same vertices through the same shader give the same depths: LEQUAL draws the tint over
  // the body. No culling: a folded part is inside out, its front faces point away.
  glDepthFunc(GL_LEQUAL);
  for (BodyView& v : views_) {
    if (v.tintTriangles.empty()) continue;
    if (!v.tint) v.tint = std::make_unique<render::MeshBuffer>();
    if (!v.tintUploaded) {
      v.tint->setIndices(v.tintTriangles.data(), v.tintTriangles.size() / 3);
      v.tintUploaded = true;
    }
    // The positions every frame the body's are (they move between checks).
    v.tint->setVertices(v.vertices.data(), v.normals.data(),
                        static_cast<std::size_t>(v.vertices.rows()));
    meshRenderer_->draw(*v.tint, kFoldColour);
  }
  glDepthFunc(GL_LESS);
}

}  // namespace sb::app
