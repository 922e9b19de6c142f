// The changing part of a billiards table: ball states, simulated time, and the events a
// simulation reports.
#ifndef SPORTSIM_SIM_BILLIARDS_STATE_H_
#define SPORTSIM_SIM_BILLIARDS_STATE_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "Eigen/Core"
#include "Eigen/Geometry"

namespace sportsim::billiards {

/// What a ball is doing. The ball-cloth law (cloth.h) differs per state.
enum class MotionState : uint8_t {
  kStationary,  ///< v = 0, omega = 0
  kSpinning,    ///< v = 0, only omega_z != 0 (it decays)
  kSliding,     ///< the contact point slips: u = v + omega x (-R z^) != 0
  kRolling,     ///< u = 0: omega_xy = z^ x v / R
  kAirborne,    ///< reserved: jumps are not modelled (the slate absorbs vertical velocity)
  kPocketed,    ///< in a pocket (or off an open table); takes no further part
};
std::string_view MotionStateName(MotionState s);  ///< "stationary", "spinning", ...

/// The ball's centre moves (sliding or rolling).
inline bool IsTranslating(MotionState s) {
  return s == MotionState::kSliding || s == MotionState::kRolling;
}
/// The ball moves in any way the cloth law acts on (translating or spinning in place).
inline bool IsMoving(MotionState s) { return IsTranslating(s) || s == MotionState::kSpinning; }

/// One ball. Vectors in the table frame; position z = R on the cloth.
struct Ball {
  std::string id;             ///< "cue", "1" .. "15", "red1", "yellow", ...
  Eigen::Vector3d r = Eigen::Vector3d::Zero();  ///< position of the centre (m)
  Eigen::Vector3d v = Eigen::Vector3d::Zero();  ///< velocity (m/s)
  Eigen::Vector3d w = Eigen::Vector3d::Zero();  ///< angular velocity, world frame (rad/s)
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  ///< orientation (body to table)
  MotionState state = MotionState::kStationary;
  int pocket = -1;            ///< index into TableSpec::pockets once pocketed; -1 off the table
};

/// All balls and the simulated time. Balls keep their index for the whole simulation.
struct TableState {
  std::vector<Ball> balls;
  double t_s = 0.0;  ///< simulated time (s)

  /// Index of the ball with this id, or -1.
  int Find(std::string_view id) const;
  /// True when every ball is stationary or pocketed.
  bool AtRest() const;
};

enum class EventKind : uint8_t {
  kBallBall,     ///< two balls collide (a, b)
  kBallCushion,  ///< ball a hits cushion segment `other`
  kBallPocket,   ///< ball a falls into pocket `other` (-1: leaves an open table)
  kTransition,   ///< ball a changes motion state from `from` to `to`
};
std::string_view EventKindName(EventKind k);  ///< "ball_ball", "ball_cushion", ...

/// Something that happened at an instant. Velocities are the ones just after the event.
struct Event {
  double t_s = 0.0;
  EventKind kind = EventKind::kTransition;
  int a = -1;      ///< ball index
  int b = -1;      ///< second ball index (ball_ball)
  int other = -1;  ///< cushion segment or pocket index
  MotionState from = MotionState::kStationary;
  MotionState to = MotionState::kStationary;
  Eigen::Vector2d va = Eigen::Vector2d::Zero();  ///< ball a's velocity after (m/s)
  Eigen::Vector2d vb = Eigen::Vector2d::Zero();  ///< ball b's velocity after (m/s)
  Eigen::Vector2d ra = Eigen::Vector2d::Zero();  ///< ball a's centre at the event (m)
};

/// Appends ball i's change of motion state (from `from` to b.state) at t_s; nothing when the
/// state did not change.
void RecordTransition(double t_s, int i, MotionState from, const Ball& b,
                      std::vector<Event>* events);

/// Positions of every ball at one instant (the sampled trajectory).
struct Sample {
  double t_s = 0.0;
  std::vector<Eigen::Vector2d> r;   ///< per ball, in ball index order (m)
  std::vector<MotionState> state;   ///< per ball
};

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_STATE_H_
