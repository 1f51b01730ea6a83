#include "sim/scene/frame_export.h"

#include <cstdint>
#include <cstdio>
#include <ostream>

#include "sim/base/file_io.h"

namespace sb {

namespace {

void writePod(std::ostream& out, const void* data, size_t bytes) {
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
}

}  // namespace

void writeFrame(const Scene& scene, const std::string& path, FrameFormat format) {
  const World& w = scene.world;
  writeFileAtomic(path, [&](std::ostream& out) {
    if (format == FrameFormat::Obj) {
      char line[128];
      std::snprintf(line, sizeof line, "# softbody frame, time %.9g s\n", w.time());
      out << line;
      int base = 1;
      for (const SceneBody& b : scene.bodies) {
        const ConstPointsRef x = w.positions(b.handle);
        out << "o " << w.name(b.handle) << "\n";
        for (int i = 0; i < x.rows(); ++i) {
          std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", double(x(i, 0)), double(x(i, 1)),
                        double(x(i, 2)));
          out << line;
        }
        for (const auto& t : b.cageTriangles)
          out << "f " << t[0] + base << ' ' << t[1] + base << ' ' << t[2] + base << "\n";
        base += static_cast<int>(x.rows());
      }
    } else {
      writePod(out, "SBFRAME1", 8);
      const std::uint32_t bodies = static_cast<std::uint32_t>(scene.bodies.size());
      const double time = w.time();
      writePod(out, &bodies, 4);
      writePod(out, &time, 8);
      for (const SceneBody& b : scene.bodies) {
        const ConstPointsRef x = w.positions(b.handle);
        const std::uint32_t n = static_cast<std::uint32_t>(x.rows());
        writePod(out, &n, 4);
        for (int i = 0; i < x.rows(); ++i) {
          const float p[3] = {x(i, 0), x(i, 1), x(i, 2)};
          writePod(out, p, sizeof p);
        }
      }
    }
  });
}

}  // namespace sb
