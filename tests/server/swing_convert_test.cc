#include "server/swing/convert.h"

#include <cmath>
#include <limits>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/core/units.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(SwingConvertTest, EmptyRequestIsTheChapterSwing) {
  absl::StatusOr<SwingJob> job = SwingJobFromProto(v1::SimulateSwingRequest());
  ASSERT_TRUE(job.ok()) << job.status();
  const swing::SwingParams d;
  EXPECT_EQ(job->model.params().arm_length_m, d.arm_length_m);
  EXPECT_EQ(job->model.params().gamma_rad, d.gamma_rad);
  EXPECT_EQ(job->model.effects(), 0u);
  EXPECT_EQ(job->program.breakpoints(), std::vector<double>{0.1});
  EXPECT_EQ(job->solver.integrator, swing::SwingIntegrator::kRk4);
  EXPECT_FALSE(job->solver.accuracy.dt_s.has_value());
  EXPECT_EQ(job->run.stop, swing::SwingStop::kImpact);
  EXPECT_EQ(job->run.duration_s, 2.0);
  EXPECT_EQ(job->run.sample_stride, 1);  // 800 steps: under the automatic limit
}

TEST(SwingConvertTest, CarriesEveryField) {
  v1::SimulateSwingRequest r;
  r.mutable_parameters()->set_gamma_deg(120);
  r.mutable_parameters()->set_club_length_m(1.0);
  r.mutable_solver()->set_integrator(v1::SWING_INTEGRATOR_BOOK);
  r.mutable_solver()->set_dt_s(0.001);
  r.add_disabled_effects(v1::SWING_EFFECT_GRAVITY);
  r.add_disabled_effects(v1::SWING_EFFECT_WRIST_TORQUE);
  r.set_stop(v1::SWING_STOP_DURATION);
  auto* qa = r.mutable_torques()->mutable_qalpha();
  qa->set_interpolation(v1::INTERPOLATION_PIECEWISE_LINEAR);
  qa->add_knots()->set_torque_nm(10);
  auto* k = qa->add_knots();
  k->set_t_s(0.2);
  k->set_torque_nm(50);
  absl::StatusOr<SwingJob> job = SwingJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_DOUBLE_EQ(job->model.params().gamma_rad, DegToRad(120));
  EXPECT_EQ(job->model.params().club_length_m, 1.0);
  EXPECT_EQ(job->model.effects(), swing::kSwingDisableGravity | swing::kSwingDisableWristTorque);
  EXPECT_EQ(job->solver.integrator, swing::SwingIntegrator::kBook);
  EXPECT_EQ(*job->solver.accuracy.dt_s, 0.001);
  EXPECT_EQ(job->run.stop, swing::SwingStop::kDuration);
  EXPECT_EQ(job->run.duration_s, 0.5);
  EXPECT_NEAR(job->program.At(1, 0.15).q_alpha, 40.0, 1e-12);  // ramp 10 -> 50 over 0.2 s
  EXPECT_EQ(job->program.At(1, 0.15).q_beta, 0.0);              // chapter qbeta kept, switched
}

TEST(SwingConvertTest, AutomaticStrideBoundsTheSampleCount) {
  v1::SimulateSwingRequest r;
  r.mutable_solver()->set_dt_s(1e-5);
  absl::StatusOr<SwingJob> job = SwingJobFromProto(r);
  ASSERT_TRUE(job.ok());
  EXPECT_EQ(job->run.sample_stride, 40);  // 2 s / 1e-5 s = 200000 steps -> 5000 samples
}

struct BadRequest {
  const char* name;
  void (*edit)(v1::SimulateSwingRequest*);
  const char* message;
};

class SwingConvertRejectsTest : public ::testing::TestWithParam<BadRequest> {};

TEST_P(SwingConvertRejectsTest, InvalidArgumentNamingTheField) {
  v1::SimulateSwingRequest r;
  GetParam().edit(&r);
  absl::StatusOr<SwingJob> job = SwingJobFromProto(r);
  ASSERT_FALSE(job.ok());
  EXPECT_EQ(job.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(job.status().message(), HasSubstr(GetParam().message));
}

INSTANTIATE_TEST_SUITE_P(
    Fields, SwingConvertRejectsTest,
    ::testing::Values(
        BadRequest{"nan_length", [](auto* r) { r->mutable_parameters()->set_arm_length_m(kNan); },
                   "parameters.arm_length_m must be finite"},
        BadRequest{"neg_mass", [](auto* r) { r->mutable_parameters()->set_club_mass_kg(-1); },
                   "parameters.club_mass_kg"},
        BadRequest{"inf_gamma", [](auto* r) { r->mutable_parameters()->set_gamma_deg(kInf); },
                   "parameters.gamma_deg must be finite and in [-360, 360] deg"},
        BadRequest{"big_beta0", [](auto* r) { r->mutable_parameters()->set_beta0_deg(400); },
                   "parameters.beta0_deg"},
        BadRequest{"unknown_effect", [](auto* r) { r->mutable_disabled_effects()->Add(99); },
                   "disabled_effects[0]: unknown effect 99"},
        BadRequest{"nan_torque",
                   [](auto* r) { r->mutable_torques()->mutable_qalpha()->add_knots()->set_torque_nm(kNan); },
                   "torques.qalpha.knots[0].torque_nm"},
        BadRequest{"empty_schedule",
                   [](auto* r) { r->mutable_torques()->mutable_qbeta(); },
                   "torques.qbeta.knots must have 1 to 64 knots"},
        BadRequest{"too_many_knots",
                   [](auto* r) {
                     for (int i = 0; i < 1000; ++i) r->mutable_torques()->mutable_qalpha()->add_knots()->set_t_s(i);
                   },
                   "torques.qalpha.knots must have 1 to 64 knots, got 1000"},
        BadRequest{"dt_too_big", [](auto* r) { r->mutable_solver()->set_dt_s(1.0); },
                   "solver.dt_s must be finite and in [1e-06, 0.1] s"},
        BadRequest{"tol_on_fixed", [](auto* r) { r->mutable_solver()->set_tolerance(1e-6); },
                   "solver.tolerance applies only to dp45"},
        BadRequest{"dt_on_dp45",
                   [](auto* r) {
                     r->mutable_solver()->set_integrator(v1::SWING_INTEGRATOR_DP45);
                     r->mutable_solver()->set_dt_s(0.001);
                   },
                   "solver.dt_s does not apply to dp45"},
        BadRequest{"unknown_integrator",
                   [](auto* r) {
                     // An enum value from a newer client: set through reflection, as on the wire.
                     v1::SwingSolver* s = r->mutable_solver();
                     s->GetReflection()->SetEnumValue(s, s->GetDescriptor()->FindFieldByName("integrator"), 42);
                   },
                   "solver.integrator: unknown value 42"},
        BadRequest{"nan_duration", [](auto* r) { r->set_duration_s(kNan); },
                   "duration_s must be finite and in [1e-06, 10] s"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(SwingConvertTest, ResultToProtoUsesDegreesAndKeepsRates) {
  swing::SwingRunResult r;
  swing::SwingSample s;
  s.t_s = 0.25;
  s.alpha = kPi / 2;
  s.beta = -kPi / 4;
  s.theta = kPi;
  s.phi = 0;
  s.alpha_dot = 12.5;
  s.beta_dot = -3.0;
  s.clubhead_speed_mps = 40;
  s.clubhead_vx_ground_mps = -30;
  s.clubhead_vy_ground_mps = 30;
  r.samples = {s};
  r.impact = s;
  r.steps = 7;
  v1::SimulateSwingResponse out;
  SwingResultToProto(r, 0.001, &out);
  ASSERT_EQ(out.samples_size(), 1);
  EXPECT_DOUBLE_EQ(out.samples(0).alpha_deg(), 90.0);
  EXPECT_DOUBLE_EQ(out.samples(0).beta_deg(), -45.0);
  EXPECT_DOUBLE_EQ(out.samples(0).theta_deg(), 180.0);
  EXPECT_EQ(out.samples(0).alpha_dot_rps(), 12.5);
  EXPECT_TRUE(out.has_impact());
  EXPECT_DOUBLE_EQ(out.impact().clubhead_direction_deg(), 45.0);  // up and toward the target
  EXPECT_EQ(out.steps(), 7u);
  EXPECT_EQ(out.cpu_s(), 0.001);
}

}  // namespace
}  // namespace sportsim::server

namespace sportsim::server {
namespace {

v1::SimulateFlightRequest DriverFlight() {
  v1::SimulateFlightRequest r;
  r.mutable_launch()->set_ball_speed_mps(74.66);
  r.mutable_launch()->set_launch_angle_deg(10.9);
  r.mutable_launch()->set_spin_rpm(2686);
  return r;
}

TEST(FlightConvertTest, DefaultsAreIsaSeaLevelStillAirRk4) {
  absl::StatusOr<FlightJob> job = FlightJobFromProto(DriverFlight());
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->launch.ball_speed_mps, 74.66);
  EXPECT_EQ(job->atmosphere.temperature_c, 15.0);
  EXPECT_EQ(job->atmosphere.pressure_pa, 101325.0);
  EXPECT_EQ(job->wind.speed_mps, 0.0);
  EXPECT_EQ(job->options.effects, 0u);
  EXPECT_FALSE(job->options.accuracy.dt_s.has_value());  // the default, 1e-3 s
}

TEST(FlightConvertTest, CarriesWindEffectsAndAtmosphere) {
  v1::SimulateFlightRequest r = DriverFlight();
  r.mutable_wind()->set_speed_mps(5);
  r.mutable_wind()->set_toward_deg(180);
  r.mutable_wind()->set_logarithmic_profile(true);
  r.mutable_atmosphere()->set_altitude_m(1600);
  r.add_disabled_effects(v1::FLIGHT_EFFECT_SPIN_DECAY);
  r.set_sample_interval_s(0.05);
  absl::StatusOr<FlightJob> job = FlightJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->wind.toward_deg, 180.0);
  EXPECT_EQ(job->wind.profile, golf::WindProfile::kLogarithmic);
  EXPECT_EQ(job->atmosphere.altitude_m, 1600.0);
  EXPECT_EQ(job->options.effects, golf::kFlightDisableSpinDecay);
  EXPECT_EQ(job->options.sample_interval_s, 0.05);
  EXPECT_EQ(job->options.aero.fit, golf::AeroFit::kFergusonMcNallyMcPhee2022);  // unset
  r.set_aero_fit(v1::AERO_FIT_NATHAN);
  job = FlightJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->options.aero.fit, golf::AeroFit::kNathan);
}

TEST(FlightConvertTest, RejectsBadInputNamingTheField) {
  struct Case {
    void (*edit)(v1::SimulateFlightRequest*);
    const char* message;
  };
  const Case cases[] = {
      {[](auto* r) { r->mutable_launch()->set_ball_speed_mps(std::nan("")); }, "launch.ball_speed_mps"},
      {[](auto* r) { r->mutable_launch()->set_launch_angle_deg(95); }, "launch.launch_angle_deg"},
      {[](auto* r) { r->mutable_launch()->set_spin_rpm(-1); }, "launch.spin_rpm"},
      {[](auto* r) { r->mutable_atmosphere()->set_altitude_m(1e6); }, "atmosphere.altitude_m"},
      {[](auto* r) { r->mutable_atmosphere()->set_relative_humidity(2); }, "atmosphere.relative_humidity"},
      {[](auto* r) { r->set_dt_s(1e-9); }, "dt_s must be finite and in [1e-05, 0.1] s"},
      {[](auto* r) { r->set_sample_interval_s(1e-5); }, "sample_interval_s must be finite and in [0.001, 10] s"},
      {[](auto* r) { r->mutable_disabled_effects()->Add(77); }, "disabled_effects[0]: unknown effect 77"},
      {[](auto* r) { r->set_aero_fit(static_cast<v1::AeroFit>(9)); }, "aero_fit: unknown fit 9"},
      {[](auto* r) { r->mutable_wind()->set_speed_mps(-1); }, "wind speed_mps"},
      {[](auto* r) { r->mutable_wind()->set_toward_deg(INFINITY); }, "wind toward_deg"},
  };
  for (const Case& c : cases) {
    v1::SimulateFlightRequest r = DriverFlight();
    c.edit(&r);
    absl::StatusOr<FlightJob> job = FlightJobFromProto(r);
    ASSERT_FALSE(job.ok()) << c.message;
    EXPECT_EQ(job.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(job.status().message(), HasSubstr(c.message));
  }
}

}  // namespace
}  // namespace sportsim::server
