#include "ifab/perception/dense_lm.h"

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ifab/core/random.h"

namespace ifab::internal {
namespace {

// y = a exp(b t) + c sin(d t): four parameters, many residuals, nonlinear in b and d.
struct Sample {
  double t, y;
};

std::vector<Sample> Samples(std::uint64_t seed) {
  RandomStream rng(seed);
  std::vector<Sample> out;
  for (int i = 0; i < 400; ++i) {
    const double t = 0.01 * i;
    out.push_back({t, 1.5 * std::exp(-0.7 * t) + 0.4 * std::sin(2.3 * t) + rng.Normal(0.02)});
  }
  return out;
}

struct Residual {
  double t, y;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    r[0] = x[0] * exp(x[1] * t) + x[2] * sin(x[3] * t) - y;
    return true;
  }
};

bool Evaluate(const std::vector<Sample>& samples, const Eigen::VectorXd& x, double* cost, Eigen::MatrixXd* H,
              Eigen::VectorXd* g) {
  *cost = 0.0;
  for (const auto& s : samples) {
    const double e = std::exp(x[1] * s.t), sn = std::sin(x[3] * s.t);
    const double r = x[0] * e + x[2] * sn - s.y;
    *cost += 0.5 * r * r;
    if (!H) continue;
    const Eigen::Vector4d j(e, x[0] * s.t * e, sn, x[2] * s.t * std::cos(x[3] * s.t));
    *H += j * j.transpose();
    *g += r * j;
  }
  return true;
}

TEST(DenseLm, ReachesTheMinimumCeresReachesOnTheSameProblem) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const auto samples = Samples(seed);
    const double start[4] = {1.0, -0.3, 0.2, 2.0};

    double xc[4] = {start[0], start[1], start[2], start[3]};
    ceres::Problem problem;
    for (const auto& s : samples)
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Residual, 1, 4>(new Residual{s.t, s.y}), nullptr, xc);
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
    so.max_num_iterations = 50;
    so.function_tolerance = 1e-12;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = 1e-12;
    ceres::Solver::Summary cs;
    ceres::Solve(so, &problem, &cs);
    ASSERT_TRUE(cs.IsSolutionUsable());

    Eigen::VectorXd x = Eigen::Map<const Eigen::Vector4d>(start);
    DenseLmOptions options;
    options.max_iterations = 50;
    options.function_tolerance = 1e-12;
    options.parameter_tolerance = 1e-12;
    const DenseLmSummary s = SolveDenseLm(
        [&](const Eigen::VectorXd& at, double* cost, Eigen::MatrixXd* H, Eigen::VectorXd* g) {
          return Evaluate(samples, at, cost, H, g);
        },
        x, options);
    ASSERT_TRUE(s.usable) << s.message;
    EXPECT_LT(s.final_cost, s.initial_cost);
    EXPECT_NEAR(s.final_cost, cs.final_cost, 1e-9 * cs.final_cost);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(x[k], xc[k], 1e-6) << "parameter " << k << ", seed " << seed;
    // The same iteration as Ceres's LM: about the same number of steps.
    EXPECT_LE(std::abs(s.iterations - static_cast<int>(cs.iterations.size() - 1)), 2)
        << s.message << " vs " << cs.BriefReport();
  }
}

TEST(DenseLm, SaysSoWhenTheStartCannotBeEvaluated) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  const DenseLmSummary s = SolveDenseLm([](const Eigen::VectorXd&, double*, Eigen::MatrixXd*, Eigen::VectorXd*) { return false; }, x);
  EXPECT_FALSE(s.usable);
  EXPECT_NE(s.message.find("initial point"), std::string::npos);
}

TEST(DenseLm, KeepsTheLastGoodPointWhenAStepCannotBeEvaluated) {
  // Cost (x - 3)^2 / 2, undefined beyond x = 1: every step past it is rejected, the region shrinks
  // and the solver ends below 1 with a lower cost than at the start.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(1);
  const DenseLmSummary s = SolveDenseLm(
      [](const Eigen::VectorXd& at, double* cost, Eigen::MatrixXd* H, Eigen::VectorXd* g) {
        if (at[0] > 1.0) return false;
        *cost = 0.5 * (at[0] - 3.0) * (at[0] - 3.0);
        if (H) {
          (*H)(0, 0) += 1.0;
          (*g)[0] += at[0] - 3.0;
        }
        return true;
      },
      x);
  ASSERT_TRUE(s.usable) << s.message;
  EXPECT_LE(x[0], 1.0);
  EXPECT_GT(x[0], 0.5);
  EXPECT_LT(s.final_cost, s.initial_cost);
}

}  // namespace
}  // namespace ifab::internal
