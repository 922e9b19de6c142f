// The swing flags and sample rows shared by `swing simulate` and the swing session commands
// (defined in swing_commands.cc): each builder fills its message from the flags, or returns a
// usage error.
#ifndef SPORTSIM_CLIENT_SWING_FLAGS_H_
#define SPORTSIM_CLIENT_SWING_FLAGS_H_

#include <optional>
#include <string>
#include <vector>

#include "client/cli.h"
#include "sportsim/v1/swing.pb.h"

namespace sportsim::cli {

/// --shoulder-accel --gamma --beta0 and the golfer/club flags (--arm-length --club-length
/// --arm-inertia --arm-first-moment --club-inertia --club-mass --club-first-moment --gravity).
std::optional<std::string> BuildSwingParameters(v1::SwingParameters* parameters);
/// --integrator --dt --tolerance --max-step
std::optional<std::string> BuildSwingSolver(v1::SwingSolver* solver);
/// --disable gravity,shoulder_accel,wrist_torque
std::optional<std::string> BuildSwingEffects(std::vector<v1::SwingEffect>* disabled);
/// --qalpha --qbeta --qbeta-until: the chapter's program with the flags' changes; left unset
/// (the server's default, the chapter's) when none of them is given.
std::optional<std::string> BuildTorqueProgram(v1::TorqueProgram* torques);
/// --until impact|duration, --duration
std::optional<std::string> BuildSwingStop(v1::SwingStop* stop, std::optional<double>* duration_s);

/// --club and the ball's flags (--dynamic-loft-deg --face-angle-deg --club-path-deg --cor and
/// the air flags): the ball launched at each impact. Left empty (club "") without --club, when
/// the ball's flags given are a usage error.
std::optional<std::string> BuildBallStrike(v1::BallStrike* ball);

/// The flight's air flags (defined in flight_commands.cc): --wind --temperature-c --pressure-pa
/// --humidity --altitude-m --sample-interval --aero. Shared by `flight simulate` and the ball a
/// swing launches (`swing simulate --club`).
std::optional<std::string> BuildFlightAir(v1::SimulateFlightRequest* request);
/// The text summary of a flight (carry, apex, landing).
void PrintFlightText(const v1::SimulateFlightResponse& flight);

/// --arm-length and --club-length as given (unset when not), for drawings.
std::optional<double> ArmLengthFlag();
std::optional<double> ClubLengthFlag();

/// The CSV columns of a swing sample (docs/cli.md): the header and one row, each with its newline.
std::string SwingCsvHeader();
std::string SwingCsvRow(const v1::SwingSample& s);

/// `swing create|get|list|delete|reset|start|watch|drive` (swing_session_commands.cc).
int RunSwingSession(const Context& ctx, const std::string& verb,
                    const std::vector<std::string>& args);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_SWING_FLAGS_H_
