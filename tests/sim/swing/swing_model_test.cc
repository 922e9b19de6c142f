#include "sim/swing/swing_model.h"

#include <cmath>
#include <limits>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace sportsim::swing {
namespace {

using ::testing::HasSubstr;

TEST(SwingModelTest, ChapterDefaultsAreValid) {
  absl::StatusOr<SwingModel> m = SwingModel::Create(SwingParams{});
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_DOUBLE_EQ(m->arm_static_moment(), 7.3 * 0.62 * 0.5 + 0.4 * 0.62);
  EXPECT_DOUBLE_EQ(m->g(), 9.8);
  EXPECT_DOUBLE_EQ(m->a(), 0.98);
}

TEST(SwingModelTest, SwitchedOffEffectsZeroTheirTerms) {
  const SwingModel m = *SwingModel::Create(SwingParams{}, kSwingDisableGravity | kSwingDisableShoulderAccel);
  EXPECT_EQ(m.g(), 0.0);
  EXPECT_EQ(m.a(), 0.0);
  EXPECT_FALSE(m.gravity_on());
  EXPECT_TRUE(m.wrist_torque_on());
  EXPECT_FALSE(SwingModel::Create(SwingParams{}, kSwingDisableWristTorque)->wrist_torque_on());
}

struct BadParam {
  const char* field;
  void (*set)(SwingParams*, double);
  double value;
};

class SwingModelRejectsTest : public ::testing::TestWithParam<BadParam> {};

TEST_P(SwingModelRejectsTest, NamesTheField) {
  SwingParams p;
  GetParam().set(&p, GetParam().value);
  absl::StatusOr<SwingModel> m = SwingModel::Create(p);
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(m.status().message(), HasSubstr(GetParam().field));
}

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

INSTANTIATE_TEST_SUITE_P(
    BadValues, SwingModelRejectsTest,
    ::testing::Values(
        BadParam{"arm_length_m", [](SwingParams* p, double v) { p->arm_length_m = v; }, 0.0},
        BadParam{"arm_length_m", [](SwingParams* p, double v) { p->arm_length_m = v; }, -1.0},
        BadParam{"club_length_m", [](SwingParams* p, double v) { p->club_length_m = v; }, kNan},
        BadParam{"arm_inertia_kgm2", [](SwingParams* p, double v) { p->arm_inertia_kgm2 = v; }, kInf},
        BadParam{"club_inertia_kgm2", [](SwingParams* p, double v) { p->club_inertia_kgm2 = v; }, 0.0},
        BadParam{"club_mass_kg", [](SwingParams* p, double v) { p->club_mass_kg = v; }, -0.4},
        BadParam{"gravity_mps2", [](SwingParams* p, double v) { p->gravity_mps2 = v; }, kNan},
        BadParam{"gamma_rad", [](SwingParams* p, double v) { p->gamma_rad = v; }, 100.0},
        BadParam{"shoulder_accel_mps2", [](SwingParams* p, double v) { p->shoulder_accel_mps2 = v; }, -kInf},
        // I (J + Mc R^2) = 0.08 * 1.30376 < (R S)^2 with S = 1: singular at beta = 0.
        BadParam{"singular", [](SwingParams* p, double v) { p->club_first_moment_kgm = v; }, 1.0}));

TEST(SwingModelTest, RejectsUnknownEffectBits) {
  EXPECT_EQ(SwingModel::Create(SwingParams{}, 1u << 7).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace sportsim::swing
