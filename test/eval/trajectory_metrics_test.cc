#include "core/eval/trajectory_metrics.h"

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace cblox {
namespace {

// 100 poses at 10 Hz on a smooth 3D curve with a turning, tilting camera.
StampedTrajectory groundTruth(size_t count = 100, double rate_hz = 10.0) {
  StampedTrajectory trajectory;
  for (size_t i = 0; i < count; ++i) {
    const double s = static_cast<double>(i);
    Eigen::Matrix<double, 6, 1> xi = Eigen::Matrix<double, 6, 1>::Zero();
    xi.tail<3>() << 0.2 * std::sin(0.07 * s), 0.1 * std::cos(0.05 * s), 0.06 * s;
    const Transformationd rotation = Transformationd::exp(xi);
    const Eigen::Vector3d position(2.0 * std::cos(0.1 * s), 1.5 * std::sin(0.13 * s),
                                   0.3 * std::sin(0.05 * s));
    trajectory.push_back({1000.0 + s / rate_hz, Transformationd(rotation.rotation(), position)});
  }
  return trajectory;
}

// Every pose mapped by T_E_G: the same trajectory seen from another world frame E.
StampedTrajectory inOtherFrame(const StampedTrajectory& trajectory, const Transformationd& T_E_G) {
  StampedTrajectory out;
  for (const StampedPose& pose : trajectory) out.push_back({pose.timestamp_s, T_E_G * pose.T_G_C});
  return out;
}

Transformationd someTransform() {
  Eigen::Matrix<double, 6, 1> xi;
  xi << 3.0, -1.0, 0.5, 0.3, -0.2, 1.2;
  return Transformationd::exp(xi);
}

std::vector<AssociatedPose> exactPairs(const StampedTrajectory& truth,
                                       const StampedTrajectory& estimate) {
  return associateTrajectories(truth, estimate, AssociationConfig{});
}

TEST(ErrorStatisticsTest, ComputesRmseMeanMedianStdMinMax) {
  const ErrorStatistics s = computeErrorStatistics({3.0, 1.0, 2.0, 4.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.stddev, std::sqrt(1.25));
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(computeErrorStatistics({5.0, 1.0, 2.0}).median, 2.0);
  // p90, linear between order statistics: h = 0.9 * 3 = 2.7 -> 3 + 0.7 * (4 - 3).
  EXPECT_DOUBLE_EQ(s.p90, 3.7);
  // 11 values 0..10: h = 9 exactly.
  EXPECT_DOUBLE_EQ(computeErrorStatistics({10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0}).p90, 9.0);
  EXPECT_DOUBLE_EQ(computeErrorStatistics({0.25}).p90, 0.25);
  const ErrorStatistics empty = computeErrorStatistics({});
  EXPECT_EQ(empty.count, 0u);
  EXPECT_EQ(empty.rmse, 0.0);
}

TEST(AssociationTest, NearestWithinMaxDifferenceUsesEachPoseOnce) {
  const StampedTrajectory truth = groundTruth(300, 100.0);  // 1000.00, 1000.01, ...
  // Estimate at ~33 Hz, 3 ms after every third ground-truth pose, plus poses outside.
  StampedTrajectory estimate;
  estimate.push_back({999.5, Transformationd()});
  for (size_t k = 0; k < 100; ++k) {
    estimate.push_back({truth[3 * k].timestamp_s + 0.003, truth[3 * k].T_G_C});
  }
  estimate.push_back({1010.0, Transformationd()});

  AssociationConfig options;  // nearest, 0.02 s
  std::vector<AssociatedPose> pairs = associateTrajectories(truth, estimate, options);
  ASSERT_EQ(pairs.size(), 100u);
  for (size_t k = 0; k < pairs.size(); ++k) {
    EXPECT_EQ(pairs[k].timestamp_s, estimate[k + 1].timestamp_s);
    EXPECT_TRUE(pairs[k].T_G_C_truth.isApprox(truth[3 * k].T_G_C, 0.0)) << k;
  }
  options.max_difference_s = 0.002;
  EXPECT_TRUE(associateTrajectories(truth, estimate, options).empty());
  options.time_offset_s = -0.003;  // shifts the estimate back onto the ground-truth stamps
  EXPECT_EQ(associateTrajectories(truth, estimate, options).size(), 100u);
  options.max_difference_s = -1.0;  // invalid
  EXPECT_TRUE(associateTrajectories(truth, estimate, options).empty());

  // Two estimates nearest to the same ground-truth pose: the closer one gets it, the other
  // takes the next ground-truth pose (still within 0.02 s).
  const StampedTrajectory two_truth = {{1.00, Transformationd()}, {1.01, someTransform()}};
  const StampedTrajectory two_estimates = {{1.000, Transformationd()}, {1.004, Transformationd()}};
  pairs = associateTrajectories(two_truth, two_estimates, AssociationConfig{});
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_TRUE(pairs[0].T_G_C_truth.isApprox(Transformationd(), 0.0));
  EXPECT_TRUE(pairs[1].T_G_C_truth.isApprox(someTransform(), 0.0));
}

TEST(AssociationTest, InterpolateEvaluatesGroundTruthAtEstimateTimes) {
  // Ground truth moving at 1 m/s along x, sampled at 10 Hz.
  StampedTrajectory truth;
  for (int i = 0; i <= 10; ++i) {
    truth.push_back(
        {0.1 * i, Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1 * i, 0, 0))});
  }
  const StampedTrajectory estimate = {{-0.5, Transformationd()},  // outside: dropped
                                      {0.0, Transformationd()},
                                      {0.237, Transformationd()},
                                      {0.95, Transformationd()}};
  AssociationConfig options;
  options.method = AssociationMethod::kInterpolate;
  options.max_difference_s = 0.15;
  const std::vector<AssociatedPose> pairs = associateTrajectories(truth, estimate, options);
  ASSERT_EQ(pairs.size(), 3u);
  EXPECT_NEAR(pairs[0].T_G_C_truth.translation().x(), 0.0, 1e-12);
  EXPECT_NEAR(pairs[1].T_G_C_truth.translation().x(), 0.237, 1e-12);
  EXPECT_NEAR(pairs[2].T_G_C_truth.translation().x(), 0.95, 1e-12);
  options.max_difference_s = 0.05;  // the 0.1 s gaps are now too long
  EXPECT_EQ(associateTrajectories(truth, estimate, options).size(), 1u);  // only t = 0 (end)
}

TEST(AteTest, RigidCopyHasZeroErrorWithSE3Alignment) {
  const StampedTrajectory truth = groundTruth();
  const Transformationd T_E_G = someTransform();
  const StampedTrajectory estimate = inOtherFrame(truth, T_E_G);
  std::string error;
  const auto ate = computeAte(exactPairs(truth, estimate), AlignmentType::kSE3, &error);
  ASSERT_TRUE(ate.has_value()) << error;
  EXPECT_EQ(ate->translation_m.count, truth.size());
  EXPECT_LT(ate->translation_m.rmse, 1e-9);
  EXPECT_LT(ate->translation_m.max, 1e-9);
  EXPECT_TRUE(ate->alignment.T_A_B.isApprox(T_E_G.inverse(), 1e-9)) << ate->alignment.T_A_B;
  // The aligned estimate is the ground truth again, rotations included.
  const StampedTrajectory aligned = applyAlignment(estimate, ate->alignment);
  for (size_t i = 0; i < truth.size(); ++i) {
    EXPECT_TRUE(aligned[i].T_G_C.isApprox(truth[i].T_G_C, 1e-9)) << i;
    EXPECT_EQ(aligned[i].timestamp_s, truth[i].timestamp_s);
  }
}

TEST(AteTest, NoAlignmentReportsAPureTranslationOffset) {
  const StampedTrajectory truth = groundTruth();
  const Transformationd shift(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.3, -0.4, 0.0));
  std::string error;
  const auto pairs = exactPairs(truth, inOtherFrame(truth, shift));
  const auto ate = computeAte(pairs, AlignmentType::kNone, &error);
  ASSERT_TRUE(ate.has_value()) << error;
  EXPECT_NEAR(ate->translation_m.rmse, 0.5, 1e-12);
  EXPECT_NEAR(ate->translation_m.mean, 0.5, 1e-12);
  EXPECT_NEAR(ate->translation_m.median, 0.5, 1e-12);
  EXPECT_NEAR(ate->translation_m.min, 0.5, 1e-12);
  EXPECT_NEAR(ate->translation_m.max, 0.5, 1e-12);
  EXPECT_NEAR(ate->translation_m.stddev, 0.0, 1e-12);
  EXPECT_TRUE(ate->alignment.T_A_B.isApprox(Transformationd(), 0.0));
  // SE3 alignment removes the offset.
  EXPECT_LT(computeAte(pairs, AlignmentType::kSE3, &error)->translation_m.rmse, 1e-9);
}

TEST(AteTest, Sim3HandlesAScaledCopy) {
  const StampedTrajectory truth = groundTruth();
  const Transformationd T_E_G = someTransform();
  StampedTrajectory estimate;  // positions scaled by 0.25 in frame E (monocular-like)
  for (const StampedPose& pose : inOtherFrame(truth, T_E_G)) {
    estimate.push_back({pose.timestamp_s,
                        Transformationd(pose.T_G_C.rotation(), 0.25 * pose.T_G_C.translation())});
  }
  std::string error;
  const auto pairs = exactPairs(truth, estimate);
  const auto sim3 = computeAte(pairs, AlignmentType::kSim3, &error);
  ASSERT_TRUE(sim3.has_value()) << error;
  EXPECT_LT(sim3->translation_m.rmse, 1e-9);
  EXPECT_NEAR(sim3->alignment.scale, 4.0, 1e-9);
  EXPECT_LT(sim3->alignment.T_A_B.rotation().angularDistance(T_E_G.inverse().rotation()), 1e-9);
  EXPECT_GT(computeAte(pairs, AlignmentType::kSE3, &error)->translation_m.rmse, 0.1);

  // evaluateTrajectory() passes the Sim3 scale to the RPE, which is then 0 too.
  TrajectoryEvaluationConfig options;
  options.alignment = AlignmentType::kSim3;
  const auto evaluation = evaluateTrajectory(truth, estimate, options, &error);
  ASSERT_TRUE(evaluation.has_value()) << error;
  EXPECT_NEAR(evaluation->rpe.options.estimate_scale, 4.0, 1e-9);
  EXPECT_LT(evaluation->rpe.translation_m.rmse, 1e-9);
  EXPECT_LT(evaluation->rpe.rotation_deg.rmse, 1e-6);
}

TEST(RpeTest, ZeroAgainstItselfAndAgainstAnotherWorldFrame) {
  const StampedTrajectory truth = groundTruth();
  std::string error;
  for (const StampedTrajectory& estimate : {truth, inOtherFrame(truth, someTransform())}) {
    const auto pairs = exactPairs(truth, estimate);
    for (const RpeDeltaUnit unit : {RpeDeltaUnit::kFrames, RpeDeltaUnit::kSeconds}) {
      RpeConfig options;
      options.unit = unit;
      options.delta = unit == RpeDeltaUnit::kFrames ? 3.0 : 0.5;
      const auto rpe = computeRpe(pairs, options, &error);
      ASSERT_TRUE(rpe.has_value()) << error;
      EXPECT_EQ(rpe->translation_m.count, unit == RpeDeltaUnit::kFrames ? 97u : 95u);
      EXPECT_LT(rpe->translation_m.max, 1e-9);
      // The rotation angle of a near-identity quaternion is accurate to ~1e-8 rad.
      EXPECT_LT(rpe->rotation_deg.max, 1e-6);
    }
  }
}

TEST(RpeTest, ConstantPerStepDriftGivesThatDrift) {
  // The estimate repeats every ground-truth step followed by a constant error D (1 cm along x,
  // 0.5 degrees about z): P_{i+1} = P_i (Q_i^-1 Q_{i+1}) D, so E_i = D for a 1-frame delta.
  const StampedTrajectory truth = groundTruth();
  const Transformationd D(Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * std::numbers::pi / 180.0,
                                                               Eigen::Vector3d::UnitZ())),
                          Eigen::Vector3d(0.01, 0.0, 0.0));
  StampedTrajectory estimate = {truth.front()};
  for (size_t i = 1; i < truth.size(); ++i) {
    estimate.push_back(
        {truth[i].timestamp_s,
         estimate.back().T_G_C * (truth[i - 1].T_G_C.inverse() * truth[i].T_G_C) * D});
  }
  const auto pairs = exactPairs(truth, estimate);
  std::string error;
  for (const RpeDeltaUnit unit : {RpeDeltaUnit::kFrames, RpeDeltaUnit::kSeconds}) {
    RpeConfig options;
    options.unit = unit;
    options.delta = unit == RpeDeltaUnit::kFrames ? 1.0 : 0.1;  // 10 Hz: the same pairs
    const auto rpe = computeRpe(pairs, options, &error);
    ASSERT_TRUE(rpe.has_value()) << error;
    EXPECT_EQ(rpe->translation_m.count, truth.size() - 1);
    EXPECT_NEAR(rpe->translation_m.rmse, 0.01, 1e-9);
    EXPECT_NEAR(rpe->translation_m.min, 0.01, 1e-9);
    EXPECT_NEAR(rpe->translation_m.max, 0.01, 1e-9);
    EXPECT_NEAR(rpe->rotation_deg.rmse, 0.5, 1e-7);
    EXPECT_NEAR(rpe->rotation_deg.max, 0.5, 1e-7);
  }
}

TEST(RpeTest, RejectsBadOptionsAndTooLongDeltas) {
  const StampedTrajectory truth = groundTruth(10);
  const auto pairs = exactPairs(truth, truth);
  std::string error;
  RpeConfig options;
  options.delta = 10.0;
  EXPECT_FALSE(computeRpe(pairs, options, &error).has_value());
  EXPECT_NE(error.find("no pose pair is 10 frames apart (10 associated poses)"), std::string::npos)
      << error;
  options.delta = 1.5;
  EXPECT_FALSE(computeRpe(pairs, options, &error).has_value());
  EXPECT_NE(error.find("whole number of frames"), std::string::npos) << error;
  options.unit = RpeDeltaUnit::kSeconds;
  options.delta = 0.0;
  EXPECT_FALSE(computeRpe(pairs, options, &error).has_value());
  EXPECT_NE(error.find("rpe.delta must be finite and > 0"), std::string::npos) << error;
  options.delta = 0.95;
  EXPECT_FALSE(computeRpe(pairs, options, &error).has_value());
  EXPECT_NE(error.find("0.95 s apart"), std::string::npos) << error;
  options.delta = 0.9;  // exactly first to last
  EXPECT_EQ(computeRpe(pairs, options, &error)->translation_m.count, 1u);
}

TEST(EvaluateTrajectoryTest, JsonHasAllKeysAndNumbers) {
  const StampedTrajectory truth = groundTruth();
  const Transformationd shift(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.3, -0.4, 0.0));
  StampedTrajectory estimate = inOtherFrame(truth, shift);
  estimate.resize(80);
  TrajectoryEvaluationConfig options;
  options.alignment = AlignmentType::kNone;
  std::string error;
  const auto evaluation = evaluateTrajectory(truth, estimate, options, &error);
  ASSERT_TRUE(evaluation.has_value()) << error;
  EXPECT_EQ(evaluation->ground_truth_poses, 100u);
  EXPECT_EQ(evaluation->estimate_poses, 80u);
  EXPECT_EQ(evaluation->matched_poses, 80u);
  EXPECT_NEAR(evaluation->ate.translation_m.rmse, 0.5, 1e-12);

  const nlohmann::ordered_json json = evaluation->toJson();
  using Json = nlohmann::ordered_json;
  // Keys in order; counts as unsigned integers; exactly representable numbers exactly.
  EXPECT_EQ(json.at("ground_truth_poses"), 100u);
  EXPECT_EQ(json.at("estimate_poses"), 80u);
  EXPECT_EQ(json.at("matched_poses"), 80u);
  EXPECT_TRUE(json.at("matched_poses").is_number_unsigned());
  std::vector<std::string> keys;
  for (const auto& item : json.items()) keys.push_back(item.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"ground_truth_poses", "estimate_poses", "matched_poses",
                                            "association", "ate", "rpe"}));
  EXPECT_EQ(json.at("association"),
            (Json{{"method", "nearest"}, {"max_difference_s", 0.02}, {"time_offset_s", 0.0}}));
  const Json& ate = json.at("ate");
  EXPECT_EQ(ate.at("alignment"), "none");
  EXPECT_EQ(ate.at("scale"), 1.0);
  EXPECT_EQ(ate.at("rotation_xyzw"), (Json{0.0, 0.0, 0.0, 1.0}));
  EXPECT_EQ(ate.at("translation_m"), (Json{0.0, 0.0, 0.0}));
  EXPECT_EQ(ate.at("pairs"), 80u);
  for (const char* key : {"rmse_m", "mean_m", "median_m", "min_m", "max_m"}) {
    EXPECT_NEAR(ate.at(key).get<double>(), 0.5, 1e-12) << key;
  }
  EXPECT_NEAR(ate.at("std_m").get<double>(), 0.0, 1e-12);
  EXPECT_EQ(ate.size(), 11u);
  const Json& rpe = json.at("rpe");
  EXPECT_EQ(rpe.at("delta"), 1.0);
  EXPECT_EQ(rpe.at("delta_unit"), "frames");
  EXPECT_EQ(rpe.at("estimate_scale"), 1.0);
  EXPECT_EQ(rpe.at("pairs"), 79u);
  for (const char* stat : {"rmse", "mean", "median", "std", "min", "max"}) {
    EXPECT_NEAR(rpe.at(std::string("translation_") + stat + "_m").get<double>(), 0.0, 1e-12)
        << stat;
    EXPECT_NEAR(rpe.at(std::string("rotation_") + stat + "_deg").get<double>(), 0.0, 1e-6) << stat;
  }
  EXPECT_EQ(rpe.size(), 16u);
  // Written and read back: the same document.
  EXPECT_EQ(Json::parse(json.dump(2)), json);
}

TEST(EvaluateTrajectoryTest, RejectsEmptyUnmatchedAndInvalidInput) {
  const StampedTrajectory truth = groundTruth();
  TrajectoryEvaluationConfig options;
  std::string error;
  EXPECT_FALSE(evaluateTrajectory(truth, {}, options, &error).has_value());
  EXPECT_NE(error.find("the estimate is empty"), std::string::npos) << error;
  EXPECT_FALSE(evaluateTrajectory({}, truth, options, &error).has_value());
  EXPECT_NE(error.find("the ground truth is empty"), std::string::npos) << error;

  StampedTrajectory late = truth;
  for (StampedPose& pose : late) pose.timestamp_s += 100.0;
  EXPECT_FALSE(evaluateTrajectory(truth, late, options, &error).has_value());
  EXPECT_NE(error.find("no estimated pose matches the ground truth (nearest, max difference "
                       "0.02 s, offset 0 s; estimate 1100.000000..1109.900000 s, ground truth "
                       "1000.000000..1009.900000 s)"),
            std::string::npos)
      << error;
  options.association.time_offset_s = -100.0;  // fixes it
  EXPECT_TRUE(evaluateTrajectory(truth, late, options, &error).has_value()) << error;

  options.association.max_difference_s = std::nan("");
  EXPECT_FALSE(evaluateTrajectory(truth, truth, options, &error).has_value());
  EXPECT_NE(error.find("association.max_difference_s must be finite and >= 0"), std::string::npos)
      << error;

  const StampedTrajectory two(truth.begin(), truth.begin() + 2);
  EXPECT_FALSE(evaluateTrajectory(two, two, TrajectoryEvaluationConfig{}, &error).has_value());
  EXPECT_NE(error.find("ATE: umeyamaAlign: se3 alignment needs at least 3 point pairs"),
            std::string::npos)
      << error;
}

}  // namespace
}  // namespace cblox
