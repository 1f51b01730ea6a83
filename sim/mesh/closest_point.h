// Closest point of a triangle to a point (Ericson, Real-Time Collision Detection §5.1.5): the
// one implementation used by contacts (float) and by mean value coordinates (double).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sb::mesh {

// Where on a triangle (a, b, c) the closest point lies. Edge k joins corners k and (k+1) mod 3.
enum class TriangleFeature : unsigned char { Face, Edge0, Edge1, Edge2, Vertex0, Vertex1, Vertex2 };

template <typename T>
struct TrianglePoint {
  Eigen::Matrix<T, 3, 1> weights;  // barycentric weights of a, b, c (summing to 1)
  TriangleFeature feature;
};

// The closest point of triangle (a, b, c) to p, by the Voronoi regions of its corners and edges.
// Inside the face region the weights come from cross products of the corners relative to p
// (sub-triangle areas), which stay accurate for points on or a hair off the face, where the
// dot-product form loses digits. A degenerate triangle (zero area) yields one of its vertices or
// edges, never NaN.
template <typename T>
TrianglePoint<T> closestPointOnTriangle(const Eigen::Matrix<T, 3, 1>& p,
                                        const Eigen::Matrix<T, 3, 1>& a,
                                        const Eigen::Matrix<T, 3, 1>& b,
                                        const Eigen::Matrix<T, 3, 1>& c) {
  using V = Eigen::Matrix<T, 3, 1>;
  const T zero(0), one(1);
  const V ab = b - a, ac = c - a, ap = p - a;
  const T d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= zero && d2 <= zero) return {V(one, zero, zero), TriangleFeature::Vertex0};
  const V bp = p - b;
  const T d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= zero && d4 <= d3) return {V(zero, one, zero), TriangleFeature::Vertex1};
  const T vc = d1 * d4 - d3 * d2;
  if (vc <= zero && d1 >= zero && d3 <= zero) {
    const T t = d1 / (d1 - d3);  // d1 − d3 > 0 here
    return {V(one - t, t, zero), TriangleFeature::Edge0};
  }
  const V cp = p - c;
  const T d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= zero && d5 <= d6) return {V(zero, zero, one), TriangleFeature::Vertex2};
  const T vb = d5 * d2 - d1 * d6;
  if (vb <= zero && d2 >= zero && d6 <= zero) {
    const T t = d2 / (d2 - d6);
    return {V(one - t, zero, t), TriangleFeature::Edge2};
  }
  const T va = d3 * d6 - d5 * d4;
  if (va <= zero && d4 - d3 >= zero && d5 - d6 >= zero) {
    const T t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {V(zero, one - t, t), TriangleFeature::Edge1};
  }
  const V n = ab.cross(ac);
  const T nn = n.dot(n);
  if (!(nn > zero)) return {V(one, zero, zero), TriangleFeature::Vertex0};  // collapsed triangle
  const T wa = (b - p).cross(c - p).dot(n) / nn;
  const T wb = (c - p).cross(a - p).dot(n) / nn;
  return {V(wa, wb, one - wa - wb), TriangleFeature::Face};
}

}  // namespace sb::mesh
