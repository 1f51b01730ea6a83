#include "sim/frame_export.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace sb {

namespace {

void writePod(std::ofstream& out, const void* data, size_t bytes) {
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
}

}  // namespace

void writeFrame(const Scene& scene, const std::string& path, FrameFormat format) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot create the file");
    const World& w = scene.world;
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
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw std::runtime_error(path + ": write failed (disk full or I/O error)");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot rename the temporary file: " + ec.message());
  }
}

}  // namespace sb
