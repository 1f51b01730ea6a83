// The Sleep phase's test of rest (sim/world/sleep_phase.h): a body is still while every particle
// stays within sleepSpeed × kTimeToSleep of where the count started; what counts is where the
// particles go, not the velocities they carry.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "sim/world/sleep_phase.h"

namespace sb {
namespace {

constexpr double kH = 1.0 / 240;  // the shipped sub-step (s)
constexpr float kSleepSpeed = 0.04f;

// One body of three particles in slot 0, awake, with the given sleep speed.
std::vector<BodySlot> oneBody() {
  auto model = std::make_shared<BodyModel>();
  model->sleepSpeed = kSleepSpeed;
  std::vector<BodySlot> slots(1);
  slots[0].alive = true;
  slots[0].model = model;
  slots[0].state.x = MatX3f::Zero(3, 3);
  slots[0].state.x(1, 0) = 0.3f;
  slots[0].state.x(2, 1) = 0.3f;
  slots[0].state.v = MatX3f::Zero(3, 3);
  return slots;
}

// Runs the phase for `seconds` with the body's positions set by where(t) and its velocities by
// speed(t) (every particle along x); returns the first time the body was asleep (−1: never).
template <typename Where, typename Speed>
double asleepAt(double seconds, const Where& where, const Speed& speed) {
  std::vector<BodySlot> slots = oneBody();
  const MatX3f start = slots[0].state.x;
  SleepScratch scratch;
  const std::vector<int> awake = {0};
  const std::vector<std::pair<int, int>> touching;
  const std::vector<char> held = {0};
  for (int k = 1; k * kH <= seconds; ++k) {
    const double t = k * kH;
    slots[0].state.x = start;
    slots[0].state.x.col(0).array() += float(where(t));
    slots[0].state.v.setZero();
    slots[0].state.v.col(0).setConstant(float(speed(t)));
    runSleepPhase(kH, true, slots, awake, touching, held, scratch);
    if (slots[0].sleep.asleep) {
      EXPECT_EQ(slots[0].state.v.norm(), 0.0f);  // velocities zeroed as it falls asleep
      return t;
    }
  }
  return -1;
}

// Ringing in place: ±0.4 of the allowed radius at 10 Hz, particles 25× faster than the sleep
// speed at the crossings. At rest by its positions; it sleeps after kTimeToSleep. (The test of
// speeds it replaced never let it sleep.)
TEST(SleepPhase, ABodyRingingInPlaceWithinTheRadiusSleeps) {
  const double amplitude = 0.4 * kSleepSpeed * kTimeToSleep, omega = 2 * M_PI * 10;
  const double t = asleepAt(
      2.0, [&](double s) { return amplitude * std::sin(omega * s); },
      [&](double s) { return amplitude * omega * std::cos(omega * s); });
  EXPECT_GT(t, kTimeToSleep - 2 * kH);
  EXPECT_LT(t, kTimeToSleep + 3 * kH);  // the count starts a sub-step in
}

// Creeping with no velocity at all (position corrections alone, as pushes out of a support
// do) at 1.2× the sleep speed: it moves, so it never sleeps. (The test of speeds put it to sleep
// after 0.5 s.)
TEST(SleepPhase, ABodyCreepingByItsPositionsAloneStaysAwake) {
  EXPECT_LT(asleepAt(
                5.0, [](double s) { return 1.2 * kSleepSpeed * s; }, [](double) { return 0.0; }),
            0.0);
}

// Drifting steadily at 0.8× the sleep speed: within the radius over any kTimeToSleep, it sleeps
// as soon as it has drifted for that long.
TEST(SleepPhase, ABodyDriftingBelowTheSleepSpeedSleeps) {
  const double t = asleepAt(
      2.0, [](double s) { return 0.8 * kSleepSpeed * s; },
      [](double) { return 0.8 * kSleepSpeed; });
  EXPECT_GT(t, kTimeToSleep - 2 * kH);
  EXPECT_LT(t, kTimeToSleep + 3 * kH);  // the count starts a sub-step in
}

// Rocking with an amplitude beyond the radius: from wherever the count starts, the swing leaves
// the radius within a period and restarts it, so the body never sleeps.
TEST(SleepPhase, ABodyRockingWiderThanTheRadiusStaysAwake) {
  const double amplitude = 1.2 * kSleepSpeed * kTimeToSleep, omega = 2 * M_PI * 1.5;
  EXPECT_LT(asleepAt(
                5.0, [&](double s) { return amplitude * std::sin(omega * s); },
                [&](double s) { return amplitude * omega * std::cos(omega * s); }),
            0.0);
}

}  // namespace
}  // namespace sb
