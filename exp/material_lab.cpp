// Material lab (experiment, not a test): the cantilever of tests/sim/test_material.cpp at one
// α, cluster cell size and frame time, with 1 to 16 sub-steps per frame, 6 s simulated, sleep off.
// Usage: material_lab [ALPHA=0.5] [CELL=0: one cluster] [DT=1/60]. Prints the tip sag per run.
// material_lab dent [ALPHA=0.3] [DT=1/60]: a plastic box's height after a drop, per sub-step.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sim/world/param_ranges.h"
#include "sim/world/world.h"

using namespace sb;

static std::vector<Vec3> boxSurface(int nx, int ny, int nz, const Vec3& size, const Vec3& origin) {
  std::vector<Vec3> p;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1)
          p.push_back(origin + Vec3(size.x() * i / (nx - 1), size.y() * j / (ny - 1),
                                    size.z() * k / (nz - 1)));
  return p;
}

// dt in `sub` sub-steps exactly (maxSubstep at its largest, 1 s: not split for dt ≤ 1 s), sleep
// off so the motion itself is measured.
WorldSettings settingsFor(double dt, int sub) {
  WorldSettings s;
  s.timeStep = dt;
  s.substeps = sub;
  s.maxSubstep = limits::maxSubstep.hi;
  s.sleep = false;
  return s;
}

// A plastic box (0.6 m lattice, linear β 0.5, 8 grid clusters) dropped 1 m onto the floor, 4 s:
// its height afterwards (the dent) at 1 to 16 sub-steps per frame.
int dent(double alpha, double dt) {
  for (int sub : {1, 2, 4, 8, 16}) {
    BodyDef def;
    def.positions = boxSurface(7, 7, 7, Vec3(0.6, 0.6, 0.6), Vec3(0, 1.0, 0));
    def.params.mode = Mode::Linear;
    def.params.alpha = alpha;
    def.params.beta = 0.5;
    def.params.plasticity = {0.02, 20.0, 0.5};
    def.clusters.kind = ClusterDef::Kind::Grid;
    def.clusters.cellSize = 0.3;
    def.clusters.overlap = 0.1;
    World world(settingsFor(dt, sub));
    world.addCollider(Collider::plane(Vec3::UnitY(), 0.0));
    const BodyHandle b = world.addBody(def);
    for (int k = 0; k < int(4.0 / dt); ++k) world.step();
    const auto x = world.positions(b);
    const double height = x.col(1).maxCoeff() - x.col(1).minCoeff();
    const double width = x.col(0).maxCoeff() - x.col(0).minCoeff();
    std::printf("dent: alpha %.3f dt %.4f substeps %2d: height %.1f mm, width %.1f mm (rest 600)\n",
                alpha, dt, sub, 1e3 * height, 1e3 * width);
  }
  return 0;
}

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "dent")
    return dent(argc > 2 ? std::atof(argv[2]) : 0.3, argc > 3 ? std::atof(argv[3]) : 1.0 / 60);
  const double alpha = argc > 1 ? std::atof(argv[1]) : 0.5;
  const double cell = argc > 2 ? std::atof(argv[2]) : 0.0;
  const double dt = argc > 3 ? std::atof(argv[3]) : 1.0 / 60;
  for (int sub : {1, 2, 4, 8, 16}) {
    BodyDef def;
    def.positions = boxSurface(21, 5, 5, Vec3(2.0, 0.4, 0.4), Vec3(0, 1, 0));
    def.params.mode = Mode::Linear;
    def.params.alpha = alpha;
    def.params.beta = 0.3;
    def.params.damping = 0.3;
    std::vector<int> tip;
    for (int i = 0; i < int(def.positions.size()); ++i) {
      if (def.positions[size_t(i)].x() < 1e-9) def.pinned.push_back(i);
      if (def.positions[size_t(i)].x() > 2.0 - 1e-9) tip.push_back(i);
    }
    if (cell > 0) {
      def.clusters.kind = ClusterDef::Kind::Grid;
      def.clusters.cellSize = cell;
      def.clusters.overlap = 0.5 * cell;
    }
    World world(settingsFor(dt, sub));
    const BodyHandle b = world.addBody(def);
    for (int k = 0; k < int(6.0 / dt); ++k) world.step();
    const auto x = world.positions(b);
    double sag = 0;
    for (int i : tip) sag += def.positions[size_t(i)].y() - x(i, 1);
    sag /= double(tip.size());
    std::printf("alpha %.3f cell %.2f dt %.4f substeps %2d (h %.5f): sag %.2f mm\n", alpha, cell,
                dt, sub, dt / sub, 1e3 * sag);
  }
}
