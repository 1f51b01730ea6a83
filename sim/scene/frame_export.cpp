#include "sim/scene/frame_export.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <string_view>

#include "sim/base/file_io.h"
#include "sim/base/types.h"

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

void writeRenderMeshesObj(const Scene& scene, const std::vector<PointsRowMajor>& meshes,
                          const std::string& path, ObjObjects objects) {
  if (meshes.size() != scene.bodies.size())
    throw std::invalid_argument(path + ": " + std::to_string(meshes.size()) +
                                " render meshes for a scene of " +
                                std::to_string(scene.bodies.size()) + " bodies");
  // The text is formed in memory with to_chars through a cursor into room sized for the longest
  // lines (no stream, printf or string append per number: a large scene's sequence is hundreds
  // of MB), then written at once.
  size_t names = 0, vertices = 0, triangles = 0;
  for (size_t b = 0; b < meshes.size(); ++b) {
    names += scene.world.name(scene.bodies[b].handle).size();
    vertices += size_t(meshes[b].rows());
    triangles += scene.renderTriangles(int(b)).size();
  }
  // A float's shortest form is at most 15 characters ("-1.17549435e-38"), an int's 11.
  std::string text(
      96 + 16 + names + 4 * meshes.size() + vertices * (2 + 3 * 16) + triangles * (2 + 3 * 12),
      '\0');
  char* at = text.data();
  char* const end = text.data() + text.size();
  auto put = [&](std::string_view s) {
    std::memcpy(at, s.data(), s.size());
    at += s.size();
  };
  at += std::snprintf(at, 96, "# softbody frame, time %.9g s\n", scene.world.time());
  if (objects == ObjObjects::One) put("o softbody\n");
  int base = 1;
  for (size_t b = 0; b < meshes.size(); ++b) {
    put(objects == ObjObjects::One ? "g " : "o ");
    put(scene.world.name(scene.bodies[b].handle));
    *at++ = '\n';
    const PointsRowMajor& x = meshes[b];
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      *at++ = 'v';
      for (int c = 0; c < 3; ++c) {
        *at++ = ' ';
        at = std::to_chars(at, end, x(i, c)).ptr;  // the shortest decimal that reads back as it
      }
      *at++ = '\n';
    }
    for (const auto& t : scene.renderTriangles(int(b))) {
      *at++ = 'f';
      for (int c = 0; c < 3; ++c) {
        *at++ = ' ';
        at = std::to_chars(at, end, t[size_t(c)] + base).ptr;
      }
      *at++ = '\n';
    }
    base += static_cast<int>(x.rows());
  }
  text.resize(size_t(at - text.data()));
  writeFileAtomic(path,
                  [&](std::ostream& out) { out.write(text.data(), std::streamsize(text.size())); });
}

namespace {

[[noreturn]] void frameFail(const std::string& name, const std::string& reason) {
  throw FrameError(name + ": " + reason);
}

Frame parseBinaryFrame(const std::string& d, const std::string& name) {
  size_t pos = 8;
  auto need = [&](size_t bytes, const char* what) {
    if (d.size() - pos < bytes) frameFail(name, std::string("the file ends inside ") + what);
  };
  need(12, "the header");
  std::uint32_t bodies = 0;
  Frame f;
  std::memcpy(&bodies, d.data() + pos, 4);
  std::memcpy(&f.time, d.data() + pos + 4, 8);
  pos += 12;
  if (!std::isfinite(f.time)) frameFail(name, "the time is not finite");
  // Each body takes at least its 4-byte count: a count the bytes cannot hold fails here.
  if (std::uint64_t(bodies) * 4 > d.size() - pos)
    frameFail(name, "the header declares " + std::to_string(bodies) +
                        " bodies, more than the file holds");
  f.bodies.resize(bodies);
  for (std::uint32_t b = 0; b < bodies; ++b) {
    need(4, "a body header");
    std::uint32_t n = 0;
    std::memcpy(&n, d.data() + pos, 4);
    pos += 4;
    if (std::uint64_t(n) * 12 > d.size() - pos)
      frameFail(name, "body " + std::to_string(b) + " declares " + std::to_string(n) +
                          " particles, more than the file holds");
    PointsRowMajor& x = f.bodies[b].positions;
    x.resize(Eigen::Index(n), 3);
    if (n > 0) std::memcpy(x.data(), d.data() + pos, size_t(n) * 12);
    pos += size_t(n) * 12;
    if (!x.allFinite()) frameFail(name, "body " + std::to_string(b) + " has a non-finite position");
  }
  if (pos != d.size())
    frameFail(name, std::to_string(d.size() - pos) + " bytes after the last body");
  return f;
}

Frame parseObjFrame(const std::string& d, const std::string& name) {
  Frame f;
  std::vector<std::vector<Vec3f>> points;
  std::string_view text(d);
  size_t pos = 0;
  int lineNo = 0, base = 0;  // 1-based index of the current object's first vertex, minus one
  long long vertices = 0;
  bool timeSeen = false;
  while (pos < text.size()) {
    const size_t end = std::min(text.find('\n', pos), text.size());
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++lineNo;
    const std::string where = "line " + std::to_string(lineNo) + ": ";
    std::vector<std::string_view> tokens;
    for (size_t i = 0; i < line.size();) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
      const size_t start = i;
      while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
      if (i > start) tokens.push_back(line.substr(start, i - start));
    }
    if (tokens.empty()) continue;
    auto number = [&](std::string_view t, double& v) {
      const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
      if (r.ec != std::errc() || r.ptr != t.data() + t.size() || !std::isfinite(v))
        frameFail(name, where + "not a finite number: '" + std::string(t.substr(0, 32)) + "'");
    };
    if (tokens[0] == "#") {
      if (!timeSeen && tokens.size() == 6 && tokens[1] == "softbody" && tokens[3] == "time") {
        number(tokens[4], f.time);
        timeSeen = true;
      }
    } else if (tokens[0] == "o") {
      f.bodies.emplace_back();
      points.emplace_back();
      f.bodies.back().name = std::string(line.substr(line.find('o') + 1));
      if (!f.bodies.back().name.empty() && f.bodies.back().name[0] == ' ')
        f.bodies.back().name.erase(0, 1);
      base = int(vertices);
    } else if (tokens[0] == "g") {
      // A group inside an object (writeRenderMeshesObj, ObjObjects::One): no new body.
    } else if (tokens[0] == "v") {
      if (f.bodies.empty()) frameFail(name, where + "a vertex before the first object");
      if (tokens.size() != 4) frameFail(name, where + "a vertex needs three numbers");
      double c[3];
      for (int a = 0; a < 3; ++a) {
        number(tokens[size_t(a) + 1], c[a]);
        if (!fitsFloat(c[a]))
          frameFail(name, where + "coordinate '" +
                              std::string(tokens[size_t(a) + 1].substr(0, 32)) +
                              "' is beyond single precision");
      }
      points.back().emplace_back(float(c[0]), float(c[1]), float(c[2]));
      if (++vertices > (1LL << 30)) frameFail(name, "too many vertices");
    } else if (tokens[0] == "f") {
      if (f.bodies.empty()) frameFail(name, where + "a face before the first object");
      if (tokens.size() != 4) frameFail(name, where + "a face needs three indices");
      std::array<int, 3> t{};
      for (int a = 0; a < 3; ++a) {
        long long i = 0;
        const std::string_view tok = tokens[size_t(a) + 1];
        const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), i);
        if (r.ec != std::errc() || r.ptr != tok.data() + tok.size() || i <= base || i > vertices)
          frameFail(name, where + "face index '" + std::string(tok.substr(0, 32)) +
                              "' is not a vertex of this object");
        t[size_t(a)] = int(i - 1 - base);
      }
      f.bodies.back().triangles.push_back(t);
    } else {
      frameFail(name, where + "unexpected '" + std::string(tokens[0].substr(0, 32)) + "'");
    }
  }
  if (!timeSeen) frameFail(name, "no '# softbody frame, time T s' line");
  for (size_t b = 0; b < points.size(); ++b) {
    PointsRowMajor& x = f.bodies[b].positions;
    x.resize(Eigen::Index(points[b].size()), 3);
    for (size_t i = 0; i < points[b].size(); ++i) x.row(Eigen::Index(i)) = points[b][i].transpose();
  }
  return f;
}

}  // namespace

Frame parseFrame(const std::string& bytes, FrameFormat format, const std::string& name) {
  if (format == FrameFormat::Binary) {
    if (bytes.size() < 8 || bytes.compare(0, 8, "SBFRAME1") != 0)
      frameFail(name, "not a binary softbody frame");
    return parseBinaryFrame(bytes, name);
  }
  return parseObjFrame(bytes, name);
}

Frame readFrame(const std::string& path) {
  std::string bytes;
  try {
    bytes = readFileBounded(path, kMaxFrameFileBytes);
  } catch (const FileError& e) {
    throw FrameError(e.what());
  }
  const bool binary = bytes.size() >= 8 && bytes.compare(0, 8, "SBFRAME1") == 0;
  return parseFrame(bytes, binary ? FrameFormat::Binary : FrameFormat::Obj, path);
}

}  // namespace sb
