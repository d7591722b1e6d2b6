// Tests of one association level: Hungarian (global) versus Maximum Likelihood (greedy), the
// P_new columns, and impossible pairs.
#include <gtest/gtest.h>

#include <limits>

#include "omnislam/core/slam/data_association.h"

namespace {

using namespace omnislam::slam;
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(slam_DataAssociation, HungarianResolvesWhatGreedyGetsWrong) {
  // Measurement 0 is slightly closer to landmark 0, but measurement 1 can only be landmark 0.
  Eigen::MatrixXd cost(2, 2);
  cost << 1.0, 2.0,  //
      1.5, 30.0;
  const std::vector<double> cost_new{20.0, 20.0};
  EXPECT_EQ(associate(cost, cost_new, AssociationMethod::kHungarian), (std::vector<int>{1, 0}));
  // ML: 0 takes landmark 0; 1 would need landmark 1 at 30 > P_new -> new landmark (a duplicate).
  EXPECT_EQ(associate(cost, cost_new, AssociationMethod::kMaximumLikelihood), (std::vector<int>{0, -1}));
}

TEST(slam_DataAssociation, NewColumnsAndForbiddenPairs) {
  Eigen::MatrixXd cost(3, 2);
  cost << 5.0, kInf,  //
      kInf, kInf,     //
      50.0, 4.0;
  const std::vector<double> cost_new{10.0, 10.0, 10.0};
  for (auto m : {AssociationMethod::kHungarian, AssociationMethod::kMaximumLikelihood}) {
    EXPECT_EQ(associate(cost, cost_new, m), (std::vector<int>{0, -1, 1}));
  }
  // Everything worse than P_new: all new.
  const std::vector<double> cheap_new{1.0, 1.0, 1.0};
  EXPECT_EQ(associate(cost, cheap_new, AssociationMethod::kHungarian), (std::vector<int>{-1, -1, -1}));
  EXPECT_EQ(associate(cost, cheap_new, AssociationMethod::kMaximumLikelihood), (std::vector<int>{-1, -1, -1}));
  // No landmarks / no measurements.
  EXPECT_EQ(associate(Eigen::MatrixXd(2, 0), {1.0, 1.0}, AssociationMethod::kHungarian), (std::vector<int>{-1, -1}));
  EXPECT_TRUE(associate(Eigen::MatrixXd(0, 3), {}, AssociationMethod::kHungarian).empty());
}

TEST(slam_DataAssociation, MoreMeasurementsThanLandmarks) {
  Eigen::MatrixXd cost(4, 1);
  cost << 3.0, 1.0, 2.0, 8.0;
  const std::vector<double> cost_new(4, 5.0);
  EXPECT_EQ(associate(cost, cost_new, AssociationMethod::kHungarian), (std::vector<int>{-1, 0, -1, -1}));
  EXPECT_EQ(associate(cost, cost_new, AssociationMethod::kMaximumLikelihood), (std::vector<int>{0, -1, -1, -1}));
}

}  // namespace
