#include "sim/scene/gltf_take.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <ostream>
#include <stdexcept>

namespace sb {

// The file: GLB header (12 bytes), the JSON chunk (8-byte header, then `jsonBytes` of JSON
// padded with spaces), the BIN chunk (8-byte header, then the buffer). The buffer holds
//   view 0: every body's triangle indices (uint32), body after body (absent without triangles);
//   view 1: the key times (float32 × frames), then the morph weights (float32 × frames ×
//           targets; every body's animation sampler shares them);
//   view 2 + k: frame k, every body's vertices (float32 x, y, z) body after body: the
//           positions for k = 0, the displacement from frame 0 (morph target k − 1) after.
// All sizes are known at the start, so the frames stream to the file as they come; only the
// accessors' min/max (required for positions) wait for the data, and the JSON is written last
// into the room kept for it, sized for the longest numbers.
struct GltfTakeWriter::Layout {
  std::vector<int> vertexCounts;
  int frames = 0;
  int written = 0;
  long long totalVertices = 0;
  size_t jsonBytes = 0;  // room for the JSON text, a multiple of 4
  size_t binBytes = 0;
  int firstPositionAccessor = 0;  // frame k, body i: firstPositionAccessor + k * bodies + i
  nlohmann::json json;
  std::vector<PointsRowMajor> firstFrame;
  std::vector<float> frameBuffer;
};

namespace {

constexpr std::uint32_t kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr std::uint32_t kFloat = 5126, kUnsignedInt = 5125;

void writeU32(AtomicFileWriter& file, std::uint32_t v) {
  const unsigned char b[4] = {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8),
                              static_cast<unsigned char>(v >> 16),
                              static_cast<unsigned char>(v >> 24)};
  file.write(b, 4);
}
// float32 data in the file's little-endian order (the machines softbody builds on are
// little-endian; a big-endian one is refused at compile time rather than writing garbage).
static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559);
void writeFloats(AtomicFileWriter& file, const float* data, size_t count) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
#error "glTF buffers are little-endian: add a byte swap here for big-endian machines"
#endif
  file.write(data, count * 4);
}

}  // namespace

std::unique_ptr<GltfTakeWriter::Layout> GltfTakeWriter::makeLayout(
    const std::string& path, const Scene& scene, const std::vector<int>& vertexCounts,
    int frameCount, double frameInterval) {
  const size_t bodies = scene.bodies.size();
  if (bodies == 0 || vertexCounts.size() != bodies || frameCount < 1 ||
      !std::isfinite(frameInterval) || frameInterval <= 0)
    throw std::invalid_argument(path +
                                ": a glTF take needs ≥ 1 body, a vertex count per body, ≥ 1 "
                                "frame and a finite frame interval > 0");
  auto layout = std::make_unique<Layout>();
  Layout& l = *layout;
  l.vertexCounts = vertexCounts;
  l.frames = frameCount;
  const int targets = frameCount - 1;
  nlohmann::json& j = l.json;
  j["asset"] = {{"version", "2.0"}, {"generator", "softbody"}};
  j["scene"] = 0;
  nlohmann::json nodes = nlohmann::json::array(), meshes = nlohmann::json::array(),
                 views = nlohmann::json::array(), accessors = nlohmann::json::array();
  nlohmann::json sceneNodes = nlohmann::json::array();

  // View 0: indices (a body without triangles is drawn as points, without indices).
  size_t indexBytes = 0;
  std::vector<int> indexAccessor(bodies, -1);
  for (size_t b = 0; b < bodies; ++b) {
    if (vertexCounts[b] < 1)
      throw std::invalid_argument(path + ": body " + std::to_string(b) + " has no vertices");
    const auto& tris = scene.renderTriangles(int(b));
    for (const auto& t : tris)
      for (int v : t)
        if (v < 0 || v >= vertexCounts[b])
          throw std::invalid_argument(path + ": body " + std::to_string(b) +
                                      "'s triangles name a vertex it does not have");
    l.totalVertices += vertexCounts[b];
    if (tris.empty()) continue;
    indexAccessor[b] = int(accessors.size());
    accessors.push_back({{"bufferView", 0},
                         {"byteOffset", indexBytes},
                         {"componentType", kUnsignedInt},
                         {"count", 3 * tris.size()},
                         {"type", "SCALAR"}});
    indexBytes += 12 * tris.size();
  }
  // A view may not be empty: without any triangle, view 0 holds only the key times (below).
  if (indexBytes > 0)
    views.push_back({{"buffer", 0},
                     {"byteOffset", 0},
                     {"byteLength", indexBytes},
                     {"target", kElementArrayBuffer}});
  const int animationView = int(views.size());
  // View 1: key times and weights.
  const size_t timeBytes = 4 * size_t(frameCount);
  const size_t frameBytes = 12 * size_t(l.totalVertices);
  // GLB sizes are 32-bit: checked (in double, which cannot overflow here) before anything of
  // the size of frames × bodies or frames² is built.
  const double wholeBuffer =
      double(indexBytes) + 4.0 * frameCount * frameCount + double(frameCount) * double(frameBytes);
  if (wholeBuffer > double(0xF0000000u))
    throw std::invalid_argument(
        path + ": the take would be " + formatBytes(std::uint64_t(wholeBuffer)) +
        ", more than a glTF binary can hold (4 GB); export fewer frames (--every) or use a "
        "point cache");
  const size_t weightBytes = 4 * size_t(frameCount) * size_t(targets);
  views.push_back(
      {{"buffer", 0}, {"byteOffset", indexBytes}, {"byteLength", timeBytes + weightBytes}});
  const int timeAccessor = int(accessors.size());
  accessors.push_back(
      {{"bufferView", animationView},
       {"componentType", kFloat},
       {"count", frameCount},
       {"type", "SCALAR"},
       {"min", nlohmann::json::array({0.0})},
       {"max", nlohmann::json::array({double(float(frameInterval * (frameCount - 1)))})}});
  const int weightAccessor = int(accessors.size());
  if (targets > 0)
    accessors.push_back({{"bufferView", animationView},
                         {"byteOffset", timeBytes},
                         {"componentType", kFloat},
                         {"count", size_t(frameCount) * size_t(targets)},
                         {"type", "SCALAR"}});
  // Views 2 + k: the frames. Placeholder min/max as long as any float printed as a double can
  // be, so the JSON's room is enough whatever the data.
  const double longest = -double(std::numeric_limits<float>::min());
  size_t offset = indexBytes + timeBytes + weightBytes;
  l.firstPositionAccessor = int(accessors.size());
  for (int k = 0; k < frameCount; ++k) {
    const int view = int(views.size());
    views.push_back({{"buffer", 0},
                     {"byteOffset", offset},
                     {"byteLength", frameBytes},
                     {"target", kArrayBuffer}});
    size_t within = 0;
    for (size_t b = 0; b < bodies; ++b) {
      accessors.push_back({{"bufferView", view},
                           {"byteOffset", within},
                           {"componentType", kFloat},
                           {"count", vertexCounts[b]},
                           {"type", "VEC3"},
                           {"min", {longest, longest, longest}},
                           {"max", {longest, longest, longest}}});
      within += 12 * size_t(vertexCounts[b]);
    }
    offset += frameBytes;
  }
  l.binBytes = offset;

  nlohmann::json samplers = nlohmann::json::array(), channels = nlohmann::json::array();
  for (size_t b = 0; b < bodies; ++b) {
    const std::string& name = scene.world.name(scene.bodies[b].handle);
    nlohmann::json primitive = {{"attributes", {{"POSITION", l.firstPositionAccessor + int(b)}}},
                                {"mode", indexAccessor[b] >= 0 ? 4 : 0}};  // triangles or points
    if (indexAccessor[b] >= 0) primitive["indices"] = indexAccessor[b];
    nlohmann::json mesh = {{"name", name}};
    if (targets > 0) {
      nlohmann::json morphs = nlohmann::json::array();
      for (int k = 1; k < frameCount; ++k)
        morphs.push_back({{"POSITION", l.firstPositionAccessor + k * int(bodies) + int(b)}});
      primitive["targets"] = morphs;
      mesh["weights"] = std::vector<double>(size_t(targets), 0.0);
      samplers.push_back(
          {{"input", timeAccessor}, {"output", weightAccessor}, {"interpolation", "LINEAR"}});
      channels.push_back({{"sampler", b}, {"target", {{"node", b}, {"path", "weights"}}}});
    }
    mesh["primitives"] = nlohmann::json::array({primitive});
    meshes.push_back(mesh);
    nodes.push_back({{"name", name}, {"mesh", b}});
    sceneNodes.push_back(b);
  }
  j["scenes"] = nlohmann::json::array({nlohmann::json{{"nodes", sceneNodes}}});
  j["nodes"] = nodes;
  j["meshes"] = meshes;
  if (targets > 0)
    j["animations"] = nlohmann::json::array({nlohmann::json{
        {"name", "softbody take"}, {"samplers", samplers}, {"channels", channels}}});
  j["buffers"] = nlohmann::json::array({nlohmann::json{{"byteLength", l.binBytes}}});
  j["bufferViews"] = views;
  j["accessors"] = accessors;
  l.jsonBytes = (j.dump().size() + 3) / 4 * 4;
  l.firstFrame.resize(bodies);
  l.frameBuffer.resize(3 * size_t(l.totalVertices));
  return layout;
}

GltfTakeWriter::GltfTakeWriter(const std::string& path, const Scene& scene,
                               const std::vector<int>& vertexCounts, int frameCount,
                               double frameInterval)
    : layout_(makeLayout(path, scene, vertexCounts, frameCount, frameInterval)), file_(path) {
  const Layout& l = *layout_;
  // The header and the JSON's room are written at finish(); zeros hold their place.
  const std::vector<char> room(12 + 8 + l.jsonBytes, 0);
  file_.write(room.data(), room.size());
  writeU32(file_, std::uint32_t(l.binBytes));
  writeU32(file_, 0x004E4942);  // "BIN\0"
  for (size_t b = 0; b < scene.bodies.size(); ++b)
    for (const auto& t : scene.renderTriangles(int(b)))
      for (int v : t) writeU32(file_, std::uint32_t(v));
  std::vector<float> animation(size_t(l.frames) * size_t(l.frames));  // times, then weights
  for (int k = 0; k < l.frames; ++k) animation[size_t(k)] = float(frameInterval * k);
  const int targets = l.frames - 1;
  for (int k = 1; k < l.frames; ++k)
    animation[size_t(l.frames) + size_t(k) * size_t(targets) + size_t(k - 1)] = 1.0f;
  writeFloats(file_, animation.data(), animation.size());
}

GltfTakeWriter::~GltfTakeWriter() = default;

void GltfTakeWriter::addFrame(const std::vector<PointsRowMajor>& meshes) {
  Layout& l = *layout_;
  if (meshes.size() != l.vertexCounts.size())
    throw std::invalid_argument(file_.path() + ": a frame of " + std::to_string(meshes.size()) +
                                " meshes for a take of " + std::to_string(l.vertexCounts.size()) +
                                " bodies");
  for (size_t b = 0; b < meshes.size(); ++b)
    if (meshes[b].rows() != l.vertexCounts[b])
      throw std::invalid_argument(file_.path() + ": body " + std::to_string(b) + " has " +
                                  std::to_string(meshes[b].rows()) + " vertices, the take " +
                                  std::to_string(l.vertexCounts[b]));
  if (l.written == l.frames)
    throw std::logic_error(file_.path() + ": more frames than the " + std::to_string(l.frames) +
                           " declared");
  const int k = l.written;
  float* out = l.frameBuffer.data();
  for (size_t b = 0; b < meshes.size(); ++b) {
    const PointsRowMajor& x = meshes[b];
    Eigen::Array3f lo = Eigen::Array3f::Constant(std::numeric_limits<float>::infinity());
    Eigen::Array3f hi = -lo;
    for (Eigen::Index i = 0; i < x.rows(); ++i, out += 3) {
      // Frame 0 as positions, later frames as their displacement from it (morph targets).
      const Eigen::Array3f p =
          k == 0 ? Eigen::Array3f(x.row(i).transpose())
                 : Eigen::Array3f((x.row(i) - l.firstFrame[b].row(i)).transpose());
      out[0] = p.x();
      out[1] = p.y();
      out[2] = p.z();
      lo = lo.min(p);
      hi = hi.max(p);
    }
    if (k == 0) l.firstFrame[b] = x;
    nlohmann::json& accessor =
        l.json["accessors"][size_t(l.firstPositionAccessor) + size_t(k) * meshes.size() + b];
    accessor["min"] = {double(lo.x()), double(lo.y()), double(lo.z())};
    accessor["max"] = {double(hi.x()), double(hi.y()), double(hi.z())};
  }
  writeFloats(file_, l.frameBuffer.data(), l.frameBuffer.size());
  ++l.written;
}

void GltfTakeWriter::finish() {
  Layout& l = *layout_;
  if (l.written != l.frames)
    throw std::logic_error(file_.path() + ": " + std::to_string(l.written) + " frames of the " +
                           std::to_string(l.frames) + " declared were written");
  std::string text = l.json.dump();
  if (text.size() > l.jsonBytes)  // cannot happen: the room was sized for the longest numbers
    throw std::logic_error(file_.path() + ": the glTF JSON outgrew its room");
  text.resize(l.jsonBytes, ' ');  // the JSON chunk is padded with spaces (glTF 2.0, GLB)
  std::ostream& out = file_.stream();
  out.seekp(0);
  writeU32(file_, 0x46546C67);  // "glTF"
  writeU32(file_, 2);
  writeU32(file_, std::uint32_t(12 + 8 + l.jsonBytes + 8 + l.binBytes));
  writeU32(file_, std::uint32_t(l.jsonBytes));
  writeU32(file_, 0x4E4F534A);  // "JSON"
  file_.write(text.data(), text.size());
  file_.commit();
}

}  // namespace sb
