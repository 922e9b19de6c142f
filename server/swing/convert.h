// sportsim.v1 swing messages <-> sim/swing types. Pure translation, tested without a network.
#ifndef SPORTSIM_SERVER_SWING_CONVERT_H_
#define SPORTSIM_SERVER_SWING_CONVERT_H_

#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "sim/golf/ball_flight.h"
#include "sim/golf/club_ball_impact.h"
#include "sim/golf/golf_ball.h"
#include "sim/golf/ground.h"
#include "sim/golf/surface.h"
#include "sim/swing/swing_model.h"
#include "sim/swing/swing_simulation.h"
#include "sim/swing/swing_stepper.h"
#include "sim/swing/torque_program.h"
#include "sportsim/v1/common.pb.h"
#include "sportsim/v1/swing.pb.h"

namespace sportsim::server {

/// Everything a SimulateFlightRequest asks for, validated (field names in errors are the
/// proto's: "launch.spin_rpm", "atmosphere.altitude_m", "dt_s").
struct FlightJob {
  golf::BallSpec ball;
  golf::LaunchConditions launch;
  golf::Atmosphere atmosphere;
  golf::Wind wind;
  golf::FlightOptions options;
  /// The request's `fairway`: the flat fairway the ball rolls out on after landing.
  std::optional<golf::Surface> fairway;
};
/// A validated BallStrike: the club and face, and the flight settings, checked once; each
/// impact fills in the delivery's speed and attack angle and the flight's launch.
struct StrikeJob {
  golf::ClubSpec club;
  golf::ClubDelivery delivery;
  FlightJob flight;
};

/// Everything a SimulateSwingRequest asks for, validated.
struct SwingJob {
  swing::SwingModel model;
  swing::TorqueProgram program;
  swing::SwingSolverOptions solver;
  swing::SwingRunOptions run;
  std::optional<StrikeJob> strike;  // the request's `ball`, when set
};

/// BallStrike -> validated StrikeJob; errors name "ball.<field>".
absl::StatusOr<StrikeJob> StrikeJobFromProto(const v1::BallStrike& strike);
/// Launches and flies the ball from the swing's impact. Never fails: a delivery the impact or
/// flight model refuses is reported in `out->error`.
void LaunchBall(const StrikeJob& job, const swing::SwingSample& impact, v1::BallLaunch* out);

/// Parameters (chapter defaults for unset fields) -> validated model. Field names in errors are
/// the proto's (e.g. "parameters.gamma_deg").
absl::StatusOr<swing::SwingModel> SwingModelFromProto(const v1::SwingParameters& params,
                                                      const google::protobuf::RepeatedField<int>&
                                                          disabled_effects);
absl::StatusOr<swing::TorqueProgram> TorqueProgramFromProto(const v1::TorqueProgram& program,
                                                            bool has_program);
absl::StatusOr<swing::SwingSolverOptions> SwingSolverFromProto(const v1::SwingSolver& solver);
absl::StatusOr<SwingJob> SwingJobFromProto(const v1::SimulateSwingRequest& request);

void SampleToProto(const swing::SwingSample& s, v1::SwingSample* out);
void ImpactToProto(const swing::SwingSample& s, v1::SwingImpact* out);
void SwingResultToProto(const swing::SwingRunResult& result, double cpu_s,
                        v1::SimulateSwingResponse* out);

absl::StatusOr<FlightJob> FlightJobFromProto(const v1::SimulateFlightRequest& request);
void FlightResultToProto(const golf::FlightResult& result, double cpu_s,
                         v1::SimulateFlightResponse* out);
/// A ground event and a rest as the wire carries them (SimulateGolfShot, a flight's roll-out).
void GroundEventToProto(const golf::GroundEvent& e, v1::GolfEvent* out);
void GroundRestToProto(const golf::GroundResult& g, const std::string& surface,
                       v1::GolfRest* out);
/// `fairway` ("", firm, normal, soft) -> the surface, nullopt for ""; errors name `field`.
absl::StatusOr<std::optional<golf::Surface>> FairwayFromProto(std::string_view field,
                                                             const std::string& fairway);
/// With job.fairway: the ball from the flight's landing to rest on that flat fairway (the
/// flight's frame, no hole), into total_m, rest and ground_events. OK and nothing without one.
absl::Status RollOutToProto(const FlightJob& job, const golf::FlightResult& flight,
                            v1::SimulateFlightResponse* out);

/// The swing parameters with units, defaults and ranges, for GetInfo.
std::vector<v1::ParameterInfo> SwingParameterInfo();
/// Names of the swing effects, as `--disable` takes them.
std::vector<std::string> SwingEffectNames();

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_SWING_CONVERT_H_
