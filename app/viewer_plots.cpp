// "See what the solver does": per-frame plots of the last 10 s — kinetic energy (the scene's
// and each body's), linear and angular momentum, body–body contacts, the deepest contact as
// detected, and the step's wall time.
#include <imgui.h>

#include <cmath>
#include <cstdio>

#include "app/viewer_app.h"

namespace sb::app {

void ViewerApp::clearPlots() {
  for (PlotHistory* p : {&plots_.kinetic, &plots_.linearMomentum, &plots_.angularMomentum,
                         &plots_.contacts, &plots_.deepestContact, &plots_.stepMs})
    p->clear();
  plots_.bodyKinetic.assign(scene_.bodies.size(), PlotHistory{});
}

void ViewerApp::samplePlots() {
  const World& world = scene_.world;
  if (plots_.bodyKinetic.size() != scene_.bodies.size()) clearPlots();
  double kinetic = 0.0;
  Vec3 momentum = Vec3::Zero(), spin = Vec3::Zero();
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    const BodyHandle h = scene_.bodies[i].handle;
    const Eigen::VectorXf m = world.masses(h);
    const auto v = world.velocities(h);
    double body = 0.0;
    for (int k = 0; k < m.size(); ++k) body += 0.5 * double(m[k]) * double(v.row(k).squaredNorm());
    plots_.bodyKinetic[i].add(static_cast<float>(body));
    kinetic += body;
    momentum += world.linearMomentum(h);
    spin += world.angularMomentum(h);  // about the world origin
  }
  plots_.kinetic.add(static_cast<float>(kinetic));
  plots_.linearMomentum.add(static_cast<float>(momentum.norm()));
  plots_.angularMomentum.add(static_cast<float>(spin.norm()));
  plots_.contacts.add(static_cast<float>(world.lastContactCount()));
  plots_.deepestContact.add(static_cast<float>(1e3 * world.lastDeepestContact()));
  plots_.stepMs.add(static_cast<float>(timings_.lastSim));
}

namespace {

// One plot, scaled from 0 to its largest value; the overlay says the latest value.
void plot(const char* label, const PlotHistory& p, const char* format, const char* help) {
  char overlay[64];
  std::snprintf(overlay, sizeof overlay, format, double(p.last()));
  const float top = p.largest() > 0.0f ? p.largest() * 1.05f : 1.0f;
  ImGui::PlotLines(label, p.data(), p.count(), p.offset(), overlay, 0.0f, top, ImVec2(0, 44));
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", help);
}

}  // namespace

void ViewerApp::drawPlotsPanel() {
  plot("kinetic (J)", plots_.kinetic, "%.4g J",
       "Kinetic energy of every body, 1/2 m v^2 over the particles. Undamped bodies keep\n"
       "theirs; contacts and damping only take it away.");
  recordWidget("plotKinetic");
  plot("momentum", plots_.linearMomentum, "%.4g kg m/s",
       "|P|, the length of the sum of every particle's m v (kg m/s): changes only under\n"
       "gravity, colliders, drags and forces.");
  plot("ang. momentum", plots_.angularMomentum, "%.4g kg m2/s",
       "|L| about the world origin, sum of x cross m v (kg m^2/s).");
  plot("contacts", plots_.contacts, "%.0f",
       "Body-body contacts that carried load in the last sub-step.");
  plot("deepest (mm)", plots_.deepestContact, "%.3g mm",
       "Deepest load-carrying contact (body or collider) of the last sub-step as detected,\n"
       "before the solve pushed it out: a resting body shows g h^2 (0.17 mm at 1/240 s).");
  plot("step (ms)", plots_.stepMs, "%.2f ms", "Wall time of this frame's simulation steps.");
}

void ViewerApp::drawBodyKineticPlot(int body) {
  if (static_cast<std::size_t>(body) >= plots_.bodyKinetic.size()) return;
  plot("kinetic (J)", plots_.bodyKinetic[static_cast<std::size_t>(body)], "%.4g J",
       "This body's kinetic energy over the last 10 s.");
}

}  // namespace sb::app
