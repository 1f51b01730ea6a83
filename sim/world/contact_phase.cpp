#include "sim/world/contact_phase.h"

#include <algorithm>
#include <cmath>

#include "sim/base/parallel_for.h"

namespace sb {

namespace {

// Per-body work (bounds, grids, pairs, static contacts) forks only in worlds with at least this
// many particles.
constexpr long long kMinParallelBodyWork = 2048;
// Separation body–body contacts restore, as a fraction of the obstacle's surface spacing: a
// small positive gap keeps resting particles outside despite float round-off.
constexpr float kContactGap = 0.01f;
// An obstacle's contact grid is rebuilt once its surface has moved this many spacings.
constexpr float kGridSlack = 0.25f;
// Gauss–Seidel sweeps over a sub-step's contacts.
constexpr int kContactSweeps = 4;

// Sets up the contact view of the body in slot s.
void prepareContactBody(BodySlot& b, ContactScratch::Body& cs) {
  const BodyModel& m = *b.model;
  ContactBody& view = cs.view;
  for (int a = 0; a < 3; ++a) {
    view.x[a] = b.state.x.col(a).data();
    view.v[a] = b.state.v.col(a).data();
  }
  view.mass = m.mass.data();
  view.invMass = m.contactInvMass.data();
  view.count = m.particleCount();
  view.triangles = &m.surface;
  view.topology = &m.surfaceTopology;
  view.grid = &cs.grid;
  view.gap = kContactGap * m.spacing;
  view.meanVelocity = cs.meanVelocity;
  view.maxRelativeSpeed = cs.maxRelativeSpeed;
  // A stiff body answers a contact mostly as a whole (see sim/body_contact.h); one held by
  // pinned particles cannot move as a whole.
  prepareRigidResponse(view, m.pinned.empty() ? float(b.params.alpha) : 0.0f);
}

}  // namespace

int runContactsPhase(const WorkLayout& layout, const ContactSettings& settings, double h,
                     std::vector<BodySlot>& slots, const std::vector<int>& order,
                     ContactScratch& scratch) {
  if (!settings.bodyContact || order.size() < 2) return 0;
  std::vector<ContactScratch::Body>& contactScratch = scratch.bodies;
  contactScratch.resize(slots.size());
  const int minParallel = layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX;
  // Bounds and speeds of every body (serial: a light pass, not worth a fork/join).
  for (int k = 0; k < static_cast<int>(order.size()); ++k) {
    const int s = order[size_t(k)];
    const BodyState& st = slots[size_t(s)].state;
    ContactScratch::Body& cs = contactScratch[size_t(s)];
    const BodyModel& m = *slots[size_t(s)].model;
    cs.box.setEmpty();
    Eigen::Vector3f momentum = Eigen::Vector3f::Zero();
    for (int i = 0; i < st.x.rows(); ++i) {
      cs.box.extend(st.x.row(i).transpose());
      momentum += m.mass[i] * st.v.row(i).transpose();
    }
    cs.meanVelocity = momentum / float(m.totalMass);
    float speed2 = 0, relative2 = 0;
    for (int i = 0; i < st.x.rows(); ++i) {
      speed2 = std::max(speed2, st.v.row(i).squaredNorm());
      relative2 = std::max(relative2, (st.v.row(i).transpose() - cs.meanVelocity).squaredNorm());
    }
    cs.maxSpeed = std::sqrt(speed2);
    cs.maxRelativeSpeed = std::sqrt(relative2);
    cs.obstacle = false;
    cs.involved = false;
  }
  // A particle moves at most h·maxSpeed in this sub-step, and so does the surface it meets.
  // Boxes grow by the grid's base reach (a quarter spacing) plus twice that travel, so no pair
  // that can touch within the sub-step is missed; each particle then looks only as far as its
  // own speed needs (findContacts).
  float maxSpeed = 0;
  for (int s : order) maxSpeed = std::max(maxSpeed, contactScratch[size_t(s)].maxSpeed);
  const float travel = 2.0f * float(h) * maxSpeed;
  auto reachOf = [&](int s) {
    const BodyModel& m = *slots[size_t(s)].model;
    return m.surface.empty() ? 0.0f : 0.25f * m.spacing;
  };
  auto grown = [&](int s) {
    Eigen::AlignedBox3f box = contactScratch[size_t(s)].box;
    box.min().array() -= reachOf(s) + travel;
    box.max().array() += reachOf(s) + travel;
    return box;
  };

  // Broad phase: sweep over the grown boxes sorted along x; pairs come out in creation order.
  std::vector<int>& sweep = scratch.sweep;
  std::vector<Eigen::AlignedBox3f>& boxes = scratch.boxes;
  std::vector<int>& rank = scratch.rank;
  std::vector<ContactScratch::Pair>& contactPairs = scratch.pairs;
  sweep.assign(order.begin(), order.end());
  boxes.resize(slots.size());
  for (int s : order) boxes[size_t(s)] = grown(s);
  rank.resize(slots.size());
  for (size_t k = 0; k < order.size(); ++k) rank[size_t(order[k])] = int(k);
  std::sort(sweep.begin(), sweep.end(), [&](int a, int b) {
    const float ma = boxes[size_t(a)].min().x(), mb = boxes[size_t(b)].min().x();
    return ma != mb ? ma < mb : rank[size_t(a)] < rank[size_t(b)];
  });
  contactPairs.clear();
  for (size_t i = 0; i < sweep.size(); ++i) {
    const int a = sweep[i];
    for (size_t j = i + 1; j < sweep.size(); ++j) {
      const int b = sweep[j];
      if (boxes[size_t(b)].min().x() > boxes[size_t(a)].max().x()) break;
      if (!boxes[size_t(a)].intersects(boxes[size_t(b)])) continue;
      const int first = rank[size_t(a)] < rank[size_t(b)] ? a : b;
      const int second = first == a ? b : a;
      if (!slots[size_t(second)].model->surface.empty()) contactPairs.push_back({first, second});
      if (!slots[size_t(first)].model->surface.empty()) contactPairs.push_back({second, first});
    }
  }
  std::sort(contactPairs.begin(), contactPairs.end(),
            [&](const ContactScratch::Pair& x, const ContactScratch::Pair& y) {
              const int xa = std::min(rank[size_t(x.probe)], rank[size_t(x.obstacle)]);
              const int ya = std::min(rank[size_t(y.probe)], rank[size_t(y.obstacle)]);
              if (xa != ya) return xa < ya;
              const int xb = std::max(rank[size_t(x.probe)], rank[size_t(x.obstacle)]);
              const int yb = std::max(rank[size_t(y.probe)], rank[size_t(y.obstacle)]);
              if (xb != yb) return xb < yb;
              return rank[size_t(x.probe)] < rank[size_t(y.probe)];
            });
  if (contactPairs.empty()) return 0;

  // Each obstacle's grid covers only where its probes' particles are.
  std::vector<int>& obstacles = scratch.obstacles;
  std::vector<int>& involved = scratch.involved;
  obstacles.clear();
  involved.clear();
  for (const ContactScratch::Pair& p : contactPairs) {
    ContactScratch::Body& cs = contactScratch[size_t(p.obstacle)];
    if (!cs.obstacle) {
      obstacles.push_back(p.obstacle);
      cs.region.setEmpty();
    }
    cs.obstacle = true;
    Eigen::AlignedBox3f probeBox = contactScratch[size_t(p.probe)].box;
    probeBox.min().array() -= travel;
    probeBox.max().array() += travel;
    cs.region.extend(probeBox);
    for (int s : {p.probe, p.obstacle})
      if (!contactScratch[size_t(s)].involved) {
        contactScratch[size_t(s)].involved = true;
        involved.push_back(s);
      }
  }
  std::sort(involved.begin(), involved.end(),
            [&](int a, int b) { return rank[size_t(a)] < rank[size_t(b)]; });
  for (int s : involved) prepareContactBody(slots[size_t(s)], contactScratch[size_t(s)]);
  parallelFor(static_cast<int>(obstacles.size()), minParallel, [&](int k) {
    const int s = obstacles[size_t(k)];
    const BodyModel& m = *slots[size_t(s)].model;
    const MatX3f& x = slots[size_t(s)].state.x;
    ContactScratch::Body& cs = contactScratch[size_t(s)];
    // The grid is kept while the surface has moved less than a quarter spacing since it was
    // built and the region still fits: lookups then widen by that drift (findContacts), so
    // resting and slowly moving bodies skip the rebuild.
    float drift = 0;
    const bool reusable = cs.gridModel == &m && cs.gridRegion.contains(cs.region);
    if (reusable) drift = std::sqrt((x - cs.gridPositions).rowwise().squaredNorm().maxCoeff());
    if (!reusable || !(drift <= kGridSlack * m.spacing)) {
      cs.gridRegion = cs.region;
      cs.gridRegion.min().array() -= kGridSlack * m.spacing;
      cs.gridRegion.max().array() += kGridSlack * m.spacing;
      // Cells of one spacing: a triangle grown by its reach (a quarter spacing) lands in at most
      // 3×3×3 cells, and a cell holds a dozen or two triangles (most rejected by their boxes).
      cs.grid.build(m.surface, x.col(0).data(), x.col(1).data(), x.col(2).data(), reachOf(s),
                    m.spacing, cs.gridRegion);
      cs.gridPositions = x;
      cs.gridModel = &m;
      drift = 0;
    }
    cs.view.gridDrift = drift;
  });

  // Narrow phase reads only, so pairs run in parallel; contacts then resolve one after another
  // in pair order (Gauss–Seidel), which makes the result independent of the thread count.
  std::vector<std::vector<Contact>>& pairContacts = scratch.pairContacts;
  pairContacts.resize(contactPairs.size());
  parallelFor(static_cast<int>(contactPairs.size()), minParallel, [&](int k) {
    const ContactScratch::Pair& p = contactPairs[size_t(k)];
    pairContacts[size_t(k)].clear();
    findContacts(contactScratch[size_t(p.probe)].view, contactScratch[size_t(p.obstacle)].view,
                 float(h), pairContacts[size_t(k)]);
  });
  // Several sweeps: a body pressed by several others (a stack) needs the corrections to travel
  // through it, and each sweep sees the previous sweeps' results.
  const float friction = settings.friction;
  for (int pass = 0; pass < kContactSweeps; ++pass)
    for (size_t k = 0; k < contactPairs.size(); ++k) {
      ContactBody& probe = contactScratch[size_t(contactPairs[k].probe)].view;
      ContactBody& obstacle = contactScratch[size_t(contactPairs[k].obstacle)].view;
      for (const Contact& c : pairContacts[k]) resolveContact(probe, obstacle, c, friction);
    }
  int contactCount = 0;
  for (const auto& list : pairContacts) contactCount += static_cast<int>(list.size());
  for (int s : involved) applyRigidResponse(contactScratch[size_t(s)].view);
  return contactCount;
}

void runCollidePhase(const WorkLayout& layout, const std::vector<Collider>& colliders,
                     std::vector<BodySlot>& slots, const std::vector<int>& order,
                     ContactScratch& scratch) {
  if (colliders.empty()) return;
  std::vector<ContactScratch::Body>& contactScratch = scratch.bodies;
  contactScratch.resize(slots.size());
  // Bodies are independent here: each runs its own sweeps, so any thread split gives the same
  // result. Like body–body contacts, a contact acts partly on the body's rigid motion (see
  // sim/body_contact.h): a stiff body lands and rests as a whole instead of bouncing off the
  // few particles that touch.
  parallelFor(static_cast<int>(order.size()),
              layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX, [&](int k) {
                const int s = order[size_t(k)];
                ContactScratch::Body& cs = contactScratch[size_t(s)];
                const BodyState& st = slots[size_t(s)].state;
                cs.staticContacts.clear();
                for (int p = 0; p < st.x.rows(); ++p) {
                  const Vec3 x = st.x.row(p).transpose().cast<double>();
                  for (size_t c = 0; c < colliders.size(); ++c) {
                    Vec3 n;
                    if (colliderDistance(colliders[c], x, &n) < 0.0)
                      cs.staticContacts.push_back({p, int(c)});
                  }
                }
                if (cs.staticContacts.empty()) return;
                prepareContactBody(slots[size_t(s)], cs);
                ContactBody& view = cs.view;
                for (int pass = 0; pass < kContactSweeps; ++pass)
                  for (const auto& [p, c] : cs.staticContacts) {
                    const Collider& collider = colliders[size_t(c)];
                    Vec3 n;
                    const double d =
                        colliderDistance(collider, correctedPosition(view, p).cast<double>(), &n);
                    resolveStaticContact(view, p, n.cast<float>(), float(std::min(d, 0.0)),
                                         float(collider.friction));
                  }
                applyRigidResponse(view);
              });
}

}  // namespace sb
