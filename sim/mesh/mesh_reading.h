// Shared pieces of the mesh readers (sim/mesh/*_reader.cpp): line and token splitting, number
// parsing with the readers' rules, coordinate checks, byte-order readers. Private to sim/mesh:
// the public interface is sim/mesh/mesh_io.h. A reader reports a broken file by fail(reason),
// which parseMesh turns into a MeshError naming the file.
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "sim/base/types.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::mesh::reading {

using std::string_view;

// Thrown inside the parsers; readMesh/parseMesh prefix the name.
struct ParseFail {
  std::string reason;
};
[[noreturn]] inline void fail(const std::string& reason) {
  throw ParseFail{reason};
}
inline std::string lineText(int line) {
  return "line " + std::to_string(line) + ": ";
}

inline std::string numberText(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// A coordinate every part of the program can hold: finite and within float range.
inline void checkCoordinate(double c, const std::string& where) {
  if (!std::isfinite(c)) fail(where + "coordinate " + numberText(c) + " is not finite");
  if (!fitsFloat(c))
    fail(where + "coordinate " + numberText(c) + " is beyond float range (|c| ≤ 3.4e38)");
}

inline bool isSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

// Splits text into lines ('\n'; a trailing '\r' is dropped with the other blanks).
class Lines {
 public:
  explicit Lines(string_view text, size_t start = 0) : text_(text), pos_(start) {}
  bool next(string_view& line) {
    if (pos_ >= text_.size()) return false;
    const size_t end = text_.find('\n', pos_);
    const size_t stop = end == string_view::npos ? text_.size() : end;
    line = text_.substr(pos_, stop - pos_);
    pos_ = end == string_view::npos ? text_.size() : end + 1;
    ++number_;
    return true;
  }
  int number() const { return number_; }
  size_t position() const { return pos_; }

 private:
  string_view text_;
  size_t pos_;
  int number_ = 0;
};

// Whitespace-separated tokens of one line (or of a whole text).
class Tokens {
 public:
  explicit Tokens(string_view text) : text_(text) {}
  bool next(string_view& token) {
    while (pos_ < text_.size() && (isSpace(text_[pos_]) || text_[pos_] == '\n')) ++pos_;
    if (pos_ >= text_.size()) return false;
    const size_t start = pos_;
    while (pos_ < text_.size() && !isSpace(text_[pos_]) && text_[pos_] != '\n') ++pos_;
    token = text_.substr(start, pos_ - start);
    return true;
  }
  bool empty() {
    size_t p = pos_;
    while (p < text_.size() && (isSpace(text_[p]) || text_[p] == '\n')) ++p;
    return p >= text_.size();
  }

 private:
  string_view text_;
  size_t pos_ = 0;
};

inline std::string quoted(string_view token) {
  std::string t(token.substr(0, 40));
  for (char& c : t)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return "'" + t + (token.size() > 40 ? "...'" : "'");
}

inline bool parseDouble(string_view token, double& out) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto r = std::from_chars(token.data(), token.data() + token.size(), out);
  if (r.ec == std::errc::result_out_of_range) {
    out = token[0] == '-' ? -std::numeric_limits<double>::infinity()
                          : std::numeric_limits<double>::infinity();
    return r.ptr == token.data() + token.size();
  }
  return r.ec == std::errc() && r.ptr == token.data() + token.size();
}

inline bool parseInteger(string_view token, long long& out) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto r = std::from_chars(token.data(), token.data() + token.size(), out);
  return r.ec == std::errc() && r.ptr == token.data() + token.size();
}

// A count from a header: 0 ≤ n ≤ INT32_MAX.
inline int parseCount(string_view token, const std::string& what) {
  long long n = 0;
  if (!parseInteger(token, n)) fail(what + " must be a whole number, got " + quoted(token));
  if (n < 0 || n > std::numeric_limits<int>::max())
    fail(what + " " + std::string(token) + " is out of range");
  return int(n);
}

// Adds a face (≥ 3 corners, indices checked by the caller) as a fan of triangles from its first
// corner. A polygon (≥ 4 corners) is recorded in mesh.polygonOf (TriangleMesh) so polygon mean
// value coordinates can rebuild it; a file of triangles only leaves polygonOf empty. A polygon
// must have distinct corners and a nonzero area (its triangles are checked later with the
// closed surface, but a broken polygon is reported here, where the file line is known).
inline void addFace(TriangleMesh& mesh, const std::vector<int>& face, const std::string& where) {
  const size_t k = face.size();
  if (k >= 4) {
    // Sorted (vertex, corner) pairs: a repeat is two neighbours, found in O(k log k) (a file may
    // hold one polygon of millions of corners). Reported: the first corner that repeats, with
    // its next occurrence.
    std::vector<std::pair<int, size_t>> byVertex(k);
    for (size_t c = 0; c < k; ++c) byVertex[c] = {face[c], c};
    std::sort(byVertex.begin(), byVertex.end());
    std::pair<size_t, size_t> repeat{k, k};
    for (size_t c = 1; c < k; ++c)
      if (byVertex[c].first == byVertex[c - 1].first)
        repeat = std::min(repeat, std::make_pair(byVertex[c - 1].second, byVertex[c].second));
    if (repeat.first < k)
      fail(where + "a polygon repeats a corner: corners " + std::to_string(repeat.first + 1) +
           " and " + std::to_string(repeat.second + 1) + " of " + std::to_string(k) +
           " are the same vertex (corners must be distinct)");
    // Newell's vector: twice the vector area of the polygon, planar or not.
    Eigen::Vector3d area = Eigen::Vector3d::Zero();
    double longest = 0.0;
    for (size_t a = 0; a < k; ++a) {
      const Eigen::Vector3d& p = mesh.vertices[size_t(face[a])];
      const Eigen::Vector3d& q = mesh.vertices[size_t(face[(a + 1) % k])];
      area += p.cross(q);
      longest = std::max(longest, (q - p).norm());
    }
    if (!(area.norm() > 1e-12 * longest * longest))
      fail(where + "degenerate polygon of " + std::to_string(k) + " corners (zero area)");
    if (mesh.polygonOf.empty())  // the triangles so far were faces of their own
      for (size_t t = 0; t < mesh.triangles.size(); ++t) mesh.polygonOf.push_back(int(t));
  }
  if (k >= 4 || !mesh.polygonOf.empty()) {
    const int id = mesh.polygonOf.empty() ? 0 : mesh.polygonOf.back() + 1;
    mesh.polygonOf.insert(mesh.polygonOf.end(), k - 2, id);
  }
  for (size_t c = 1; c + 1 < k; ++c) mesh.triangles.push_back({face[0], face[c], face[c + 1]});
}

// Big-endian / little-endian readers over the remaining bytes.
class Bytes {
 public:
  Bytes(string_view data, size_t pos, bool bigEndian) : d_(data), pos_(pos), big_(bigEndian) {}
  size_t left() const { return d_.size() - pos_; }
  size_t position() const { return pos_; }
  template <typename T>
  T get(const char* what) {
    if (left() < sizeof(T)) fail(std::string("the file ends inside ") + what);
    unsigned char b[sizeof(T)];
    std::memcpy(b, d_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    const bool hostLittle = true;  // x86-64 and every target the project builds for
    if (big_ == hostLittle) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }

 private:
  string_view d_;
  size_t pos_;
  bool big_;
};

// The readers: each parses a whole file's bytes (formats and rules in sim/mesh/mesh_io.h).
TriangleMesh parseObj(string_view text);
TriangleMesh parseOff(string_view text);
TriangleMesh parsePly(string_view text);
TriangleMesh parseStl(string_view text);

}  // namespace sb::mesh::reading
