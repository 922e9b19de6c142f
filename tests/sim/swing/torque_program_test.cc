#include "sim/swing/torque_program.h"

#include <limits>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace sportsim::swing {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

TEST(TorqueProgramTest, ChapterProgramSwitchesTheWristAtExactlyPointOne) {
  const TorqueProgram p = TorqueProgram::Chapter();
  EXPECT_THAT(p.breakpoints(), ElementsAre(0.1));
  ASSERT_EQ(p.num_segments(), 2);
  // The segment decides the piece: at t = 0.1 the left segment still has the old value.
  EXPECT_EQ(p.At(0, 0.1).q_beta, -10.0);
  EXPECT_EQ(p.At(1, 0.1).q_beta, 0.0);
  EXPECT_EQ(p.At(0, 0.05).q_alpha, 100.0);
  EXPECT_EQ(p.At(1, 0.3).q_alpha, 100.0);
  EXPECT_EQ(p.SegmentAt(0.0999999), 0);
  EXPECT_EQ(p.SegmentAt(0.1), 1);
}

TEST(TorqueProgramTest, PiecewiseLinearIsLinearBetweenKnotsAndConstantOutside) {
  const TorqueSchedule qa{Interpolation::kPiecewiseLinear, {{0.05, 0.0}, {0.2, 300.0}}};
  const TorqueSchedule qb{Interpolation::kPiecewiseConstant, {{0.0, -5.0}, {0.1, 0.0}}};
  absl::StatusOr<TorqueProgram> p = TorqueProgram::Create(qa, qb);
  ASSERT_TRUE(p.ok()) << p.status();
  EXPECT_THAT(p->breakpoints(), ElementsAre(0.05, 0.1, 0.2));
  EXPECT_EQ(p->At(0, 0.01).q_alpha, 0.0);                  // before the first knot
  EXPECT_NEAR(p->At(1, 0.075).q_alpha, 50.0, 1e-12);       // 2000 N m/s slope
  EXPECT_NEAR(p->At(2, 0.15).q_alpha, 200.0, 1e-12);
  EXPECT_NEAR(p->At(2, 0.2).q_alpha, 300.0, 1e-12);        // left limit at the last knot
  EXPECT_EQ(p->At(3, 0.5).q_alpha, 300.0);                 // constant after it
  EXPECT_EQ(p->At(1, 0.075).q_beta, -5.0);
  EXPECT_EQ(p->At(2, 0.15).q_beta, 0.0);
}

TEST(TorqueProgramTest, RejectsBadSchedules) {
  const TorqueSchedule ok{Interpolation::kPiecewiseConstant, {{0.0, 1.0}}};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    TorqueSchedule s;
    const char* expect;
  };
  const Case cases[] = {
      {{Interpolation::kPiecewiseConstant, {}}, "qalpha.knots must have 1 to 64"},
      {{Interpolation::kPiecewiseConstant, {{0.1, 1}, {0.1, 2}}}, "knots[1].t_s must be greater"},
      {{Interpolation::kPiecewiseConstant, {{-0.1, 1}}}, "knots[0].t_s must be finite"},
      {{Interpolation::kPiecewiseConstant, {{0.0, nan}}}, "knots[0].torque_nm must be finite"},
      {{Interpolation::kPiecewiseConstant, {{0.0, 1e6}}}, "knots[0].torque_nm"},
  };
  for (const Case& c : cases) {
    absl::StatusOr<TorqueProgram> p = TorqueProgram::Create(c.s, ok);
    ASSERT_FALSE(p.ok());
    EXPECT_EQ(p.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(p.status().message(), HasSubstr(c.expect));
  }
  TorqueSchedule many{Interpolation::kPiecewiseConstant, {}};
  for (int i = 0; i <= TorqueProgram::kMaxKnots; ++i) many.knots.push_back({0.01 * i, 0.0});
  EXPECT_THAT(TorqueProgram::Create(ok, many).status().message(), HasSubstr("qbeta.knots"));
}

}  // namespace
}  // namespace sportsim::swing
