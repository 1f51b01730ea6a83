// Mean value coordinates for closed cages with polygon (e.g. quad) faces, independent of how a
// file's polygons were triangulated. See README.md, "Quad and polygon cages".
//
// Construction (Langer, Belyaev & Seidel 2006, "Spherical barycentric coordinates"): as in the
// triangle case (Ju, Schaefer, Warren 2005) each face F contributes its mean vector
// m_F = ∫ over the face's spherical image of the unit normal = ½ Σ_edges θ_e n_e, and the
// face's share is split among its corners by weights λ_i with Σ λ_i u_i = m_F
// (u_i = unit direction from x to corner i). For a triangle the split is unique; for a polygon
// we take, for a planar face, Floater's planar mean value coordinates b_i of the point q where
// the ray from x along m_F meets the face's plane: w_i = (n·m_F) b_i / h (h = height of the
// plane over x). This is symmetric in the corners (no diagonal) and equals triangle MVC for
// triangles. Since Σ_F m_F = 0 for a closed cage, partition of unity and linear precision hold
// for any split with Σ λ_i u_i = m_F.
//
// Non-planar faces (corners further than kPlanarFaceTolerance × face size from their best
// plane) have no plane to split in: they contribute the average of the triangle MVC of all k
// fan triangulations (one from each corner; for a quad, the two diagonals equally). Still
// exact linear precision (every triangulation of the face has the same total mean vector) and
// invariant under relabelling, but not the same weights a planar face would give in the limit.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "sim/cage/mvc.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

// A face whose corners lie within this × its largest corner distance of their Newell plane is
// planar (about 1e5 ulp: exact data and files written with %.17g stay planar, float noise
// does not).
inline constexpr double kPlanarFaceTolerance = 1e-9;

// A closed polygon cage prepared for evaluating weights. Faces come from
// mesh::polygonFaces(cage) (a triangle-only cage works too and gives triangle MVC). Construct
// from a validated cage (bindMeanValue validates; this class does not).
class PolygonMeanValueCage {
 public:
  explicit PolygonMeanValueCage(const mesh::TriangleMesh& cage);

  int vertexCount() const { return static_cast<int>(vertices_.size()); }
  double diagonal() const { return diagonal_; }
  int planarFaceCount() const { return planarFaces_; }
  int nonPlanarFaceCount() const { return nonPlanarFaces_; }

  struct Scratch {
    std::vector<double> d;  // distances to the cage vertices
  };

  // Writes the vertexCount() normalised weights of x into w (Σw = 1, Σ w_j v_j = x), with the
  // same conventions, tolerances (kOnCageTolerance, kPlaneBand) and info as
  // MeanValueCage::weights. Returns false (w filled with NaN) only if the weights cannot be
  // normalised.
  bool weights(const Eigen::Vector3d& x, double* w, Scratch& scratch,
               MvcInfo* info = nullptr) const;

 private:
  // A planar piece: a planar face, or one fan triangle of a non-planar face (share 1/k).
  struct Piece {
    std::vector<int> corners;                // counter-clockwise from outside
    std::vector<Eigen::Vector2d> corners2d;  // in the frame (origin, e1, e2)
    Eigen::Vector3d origin, e1, e2, normal;  // normal: unit, outward
    double share = 1.0;
  };
  void pieceAlone(const Eigen::Vector3d& p, const Piece& f, double* out) const;
  double distanceToPiece(const Eigen::Vector3d& p, const Piece& f) const;

  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Piece> pieces_;
  int planarFaces_ = 0, nonPlanarFaces_ = 0;
  double diagonal_ = 0.0;
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();
};

// Floater's mean value coordinates (2003) of q for the planar polygon `corners` (k ≥ 3,
// either orientation), written to b[0..k): Σ b = 1, Σ b_i corners_i = q. A q on an edge (within
// 1e-12 relative) gets the edge's linear weights, on a corner weight 1 there; for a triangle
// they are the barycentric coordinates.
void planarMeanValue(const Eigen::Vector2d& q, const std::vector<Eigen::Vector2d>& corners,
                     double* b);

}  // namespace sb::cage
