#include "sim/world/collider.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace sb {

Collider Collider::plane(const Vec3& normal, double offset, double friction) {
  Collider c;
  c.shape = Shape::Plane;
  c.normal = normal.normalized();
  c.offset = offset;
  c.friction = friction;
  return c;
}

Collider Collider::box(const Vec3& centre, const Vec3& halfExtents, const Mat3& rotation,
                       double friction) {
  Collider c;
  c.shape = Shape::Box;
  c.centre = centre;
  c.halfExtents = halfExtents;
  c.rotation = rotation;
  c.friction = friction;
  return c;
}

Collider Collider::sphere(const Vec3& centre, double radius, double friction) {
  Collider c;
  c.shape = Shape::Sphere;
  c.centre = centre;
  c.radius = radius;
  c.friction = friction;
  return c;
}

Collider Collider::capsule(const Vec3& a, const Vec3& b, double radius, double friction) {
  Collider c;
  c.shape = Shape::Capsule;
  c.centre = 0.5 * (a + b);
  c.axis = 0.5 * (b - a);
  c.radius = radius;
  c.friction = friction;
  return c;
}

const char* colliderShapeName(Collider::Shape shape) {
  switch (shape) {
    case Collider::Shape::Plane:
      return "plane";
    case Collider::Shape::Box:
      return "box";
    case Collider::Shape::Sphere:
      return "sphere";
    case Collider::Shape::Capsule:
      return "capsule";
  }
  return "?";
}

double colliderDistance(const Collider& c, const Vec3& p, Vec3* normal) {
  switch (c.shape) {
    case Collider::Shape::Plane:
      *normal = c.normal;
      return c.normal.dot(p) - c.offset;
    case Collider::Shape::Sphere: {
      const Vec3 d = p - c.centre;
      const double len = d.norm();
      *normal = len > 0.0 ? Vec3(d / len) : Vec3::UnitY();
      return len - c.radius;
    }
    case Collider::Shape::Capsule: {
      const double axisLen2 = c.axis.squaredNorm();
      const double s =
          axisLen2 > 0.0 ? std::clamp((p - c.centre).dot(c.axis) / axisLen2, -1.0, 1.0) : 0.0;
      const Vec3 d = p - (c.centre + s * c.axis);
      const double len = d.norm();
      *normal = len > 0.0 ? Vec3(d / len) : Vec3::UnitY();
      return len - c.radius;
    }
    case Collider::Shape::Box: {
      const Vec3 local = c.rotation.transpose() * (p - c.centre);
      const Vec3 q = local.cwiseAbs() - c.halfExtents;
      if ((q.array() > 0.0).any()) {  // outside: distance to the closest point of the box
        const Vec3 outside = q.cwiseMax(0.0);
        Vec3 n = outside.cwiseProduct(local.cwiseSign());
        const double len = n.norm();
        *normal = c.rotation * (n / len);
        return len;
      }
      int axis = 0;  // inside: leave through the nearest face
      q.maxCoeff(&axis);
      Vec3 n = Vec3::Zero();
      n[axis] = local[axis] >= 0.0 ? 1.0 : -1.0;
      *normal = c.rotation * n;
      return q[axis];
    }
  }
  *normal = Vec3::UnitY();
  return 1.0;
}

namespace {

// Whether the surface point q of collider `index` lies inside another collider deeper than p.
bool buried(const std::vector<Collider>& colliders, int index, const Vec3& p, const Vec3& q) {
  constexpr double kTolerance = 1e-6;  // metres: round-off of points on a shared surface
  for (int j = 0; j < static_cast<int>(colliders.size()); ++j) {
    if (j == index) continue;
    Vec3 n;
    const double atQ = colliderDistance(colliders[size_t(j)], q, &n);
    if (atQ < 0.0 &&
        atQ < std::min(0.0, colliderDistance(colliders[size_t(j)], p, &n)) - kTolerance)
      return true;
  }
  return false;
}

}  // namespace

bool exposedColliderDistance(const std::vector<Collider>& colliders, int index, const Vec3& p,
                             double* distance, Vec3* normal) {
  *distance = colliderDistance(colliders[size_t(index)], p, normal);
  return moveOntoExposedSurface(colliders, index, p, distance, normal);
}

bool moveOntoExposedSurface(const std::vector<Collider>& colliders, int index, const Vec3& p,
                            double* distance, Vec3* normal) {
  const Collider& c = colliders[size_t(index)];
  if (colliders.size() < 2) return true;
  if (c.shape == Collider::Shape::Box && *distance <= 0.0) {
    // Inside: the faces in order of depth (q: signed distances to the three face pairs' planes
    // on p's side, all ≤ 0), the first one not buried.
    const Vec3 local = c.rotation.transpose() * (p - c.centre);
    const Vec3 q = local.cwiseAbs() - c.halfExtents;
    std::array<int, 3> axes = {0, 1, 2};
    std::stable_sort(axes.begin(), axes.end(), [&](int a, int b) { return q[a] > q[b]; });
    for (int axis : axes) {
      Vec3 n = Vec3::Zero();
      n[axis] = local[axis] >= 0.0 ? 1.0 : -1.0;
      const Vec3 world = c.rotation * n;
      if (!buried(colliders, index, p, p - q[axis] * world)) {
        *distance = q[axis];
        *normal = world;
        return true;
      }
    }
    return true;  // every way out is buried: the nearest face, as colliderDistance gives
  }
  return !buried(colliders, index, p, p - *distance * *normal);
}

double colliderDistanceLowerBound(const Collider& c, const Eigen::AlignedBox3d& box) {
  const double minusInf = -std::numeric_limits<double>::infinity();
  // Distance from a point to the box (0 inside).
  auto toBox = [&](const Vec3& q) {
    return (box.min() - q).cwiseMax(q - box.max()).cwiseMax(0.0).norm();
  };
  switch (c.shape) {
    case Collider::Shape::Plane: {  // the lowest corner along the normal
      const Vec3 centre = box.center(), half = 0.5 * box.sizes();
      return c.normal.dot(centre) - c.normal.cwiseAbs().dot(half) - c.offset;
    }
    case Collider::Shape::Sphere:  // positive only when every point is outside the sphere
      return toBox(c.centre) - c.radius;
    case Collider::Shape::Capsule:  // its bounding sphere
      return toBox(c.centre) - c.axis.norm() - c.radius;
    case Collider::Shape::Box: {
      // The body's box in the collider's frame (a box around the rotated one), against the
      // collider's: the gap between them along each local axis. A point outside the collider
      // is as far as its local offset beyond the half extents, at least that gap.
      const Vec3 centre = c.rotation.transpose() * (box.center() - c.centre);
      const Vec3 half = c.rotation.transpose().cwiseAbs() * (0.5 * box.sizes());
      const Vec3 gap = (centre.cwiseAbs() - half - c.halfExtents).cwiseMax(0.0);
      const double g = gap.norm();
      return g > 0.0 ? g : minusInf;
    }
  }
  return minusInf;
}

}  // namespace sb
