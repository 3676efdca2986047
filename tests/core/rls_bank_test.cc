// RlsBank against separate Rls<N> estimators fed the same samples: every lane bit for bit, and
// the losses a bank's selector compares.
#include "core/online/rls_bank.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "core/online/rls.h"

namespace canalid::core {
namespace {

struct Variant {
  std::string name;
  RlsOptions options;
  bool structure_of_arrays;
};

std::vector<Variant> Variants(int n) {
  std::vector<Variant> v;
  RlsOptions o;
  o.initial_covariance = 1e6;
  v.push_back({"ud directional, lambda 1", o, true});
  o.forgetting = 0.7;  // r <= 1 - lambda often: directional forgetting's gain-only branch
  v.push_back({"ud directional, lambda 0.7", o, true});
  o.forgetting = 0.98;
  v.push_back({"ud directional, lambda 0.98", o, true});
  o.method = RlsMethod::kUdExponential;
  v.push_back({"ud exponential, lambda 0.98", o, true});
  o.method = RlsMethod::kUdDirectional;
  o.trace_max = 50.0;
  o.trace_min = 1e-3;
  v.push_back({"trace bounds", o, true});
  o.trace_max = std::numeric_limits<double>::infinity();
  o.trace_min = 0.0;
  o.lower = Eigen::VectorXd::Constant(n, -0.5);
  o.upper = Eigen::VectorXd::Constant(n, 2.0);
  v.push_back({"box", o, true});
  o.lower.resize(0);
  o.upper.resize(0);
  o.regressor_norm_min = 0.5;
  o.excitation_min = 1e-4;
  v.push_back({"freeze thresholds", o, true});
  o.regressor_norm_min = 0.0;
  o.excitation_min = 0.0;
  o.huber = 2.0;
  o.dead_zone = 0.05;
  v.push_back({"innovation guards (one Rls per lane)", o, false});
  o.huber = std::numeric_limits<double>::infinity();
  o.dead_zone = 0.0;
  o.method = RlsMethod::kDirectional;
  v.push_back({"covariance form (one Rls per lane)", o, false});
  return v;
}

// Every lane's state against its own Rls: equal doubles, equal counters.
template <int N>
void ExpectLanesEqual(const RlsBank<N>& bank, const std::vector<Rls<N>>& reference,
                      const std::string& where) {
  for (int l = 0; l < bank.lanes(); ++l) {
    const Rls<N>& ref = reference[static_cast<std::size_t>(l)];
    const Rls<N>& lane = bank.Lane(l);
    for (int i = 0; i < N; ++i) {
      ASSERT_EQ(bank.theta(l, i), ref.theta()(i)) << where << " lane " << l << " theta " << i;
      ASSERT_EQ(lane.theta()(i), ref.theta()(i)) << where << " lane " << l;
      ASSERT_EQ(bank.CovarianceDiagonal(l, i), ref.CovarianceDiagonal(i)) << where << " lane " << l;
    }
    typename Rls<N>::Matrix p, q;
    lane.Covariance(p);
    ref.Covariance(q);
    ASSERT_EQ(p, q) << where << " lane " << l;
    ASSERT_EQ(bank.residual_sum_of_squares(l), ref.residual_sum_of_squares()) << where;
    ASSERT_EQ(lane.innovation_variance(), ref.innovation_variance()) << where;
    const double e = lane.last_prediction_error(), e_ref = ref.last_prediction_error();
    ASSERT_TRUE(e == e_ref || (std::isnan(e) && std::isnan(e_ref))) << where << " lane " << l;
    const RlsHealth a = lane.health(), b = ref.health();
    // Counts, flags and doubles, each equal (std::tie compares them all and prints both sides).
    ASSERT_EQ(std::tie(a.updates, a.frozen_count, a.rejected_invalid, a.projections,
                       a.trace_bounded, a.clipped, a.dead_zone, a.frozen, a.wound_up),
              std::tie(b.updates, b.frozen_count, b.rejected_invalid, b.projections,
                       b.trace_bounded, b.clipped, b.dead_zone, b.frozen, b.wound_up))
        << where << " lane " << l;
    ASSERT_EQ(std::tie(a.trace_p, a.excitation, a.regressor_norm2, a.condition_estimate),
              std::tie(b.trace_p, b.excitation, b.regressor_norm2, b.condition_estimate))
        << where << " lane " << l;
  }
}

// A delay bank's data: each lane sees the same input at another delay, with drifting offsets,
// a dropped-out input now and then (NaN or absurd), a regressor that stops moving for a while
// (freeze, directional forgetting's r <= 1 - lambda) and an absurd output.
template <int N>
void RunAgainstSeparateEstimators(int lanes, RlsBankIsa isa) {
  for (const Variant& variant : Variants(N)) {
    RlsBank<N> bank(variant.options, lanes, isa);
    EXPECT_EQ(bank.structure_of_arrays(), variant.structure_of_arrays) << variant.name;
    if (variant.structure_of_arrays) {
      EXPECT_EQ(bank.isa(), isa) << variant.name;
    }
    std::vector<Rls<N>> reference(static_cast<std::size_t>(lanes), Rls<N>(variant.options));
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise(0.0, 0.05);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<double> input(2000);
    for (std::size_t k = 0; k < input.size(); ++k) {
      input[k] = (k / 7) % 2 == 0 ? 1.0 : -1.0;
      if (k > 900 && k < 1100) input[k] = 0.3;  // no excitation
    }
    std::vector<double> losses(static_cast<std::size_t>(lanes));
    int penalised = 0;
    for (int k = 40; k < 1500; ++k) {
      const double y = 0.8 * input[static_cast<std::size_t>(k - 5)] + 0.1 + noise(rng);
      const bool absurd_output = k == 300 || k == 301;
      std::vector<typename Rls<N>::Result> expected;
      for (int l = 0; l < lanes; ++l) {
        Eigen::Matrix<double, N, 1> phi;
        for (int i = 0; i < N; ++i) {
          const int lag = l + i;
          phi(i) = i == N - 1 ? 1.0 : input[static_cast<std::size_t>(k - lag % 30)];
        }
        if (unit(rng) < 0.01) phi(0) = std::numeric_limits<double>::quiet_NaN();
        if (unit(rng) < 0.005) phi(0) = 1e13;
        bank.regressors().col(l) = phi;
        expected.push_back(
            reference[static_cast<std::size_t>(l)].Update(phi, absurd_output ? 1e13 : y));
      }
      // The losses, each parameter constrained >= 0 in turn (and none), from the reference's
      // residual sum of squares and P_ii: what the selector of a bank compares.  On odd samples
      // with the update (UpdateWithLosses), on even ones after it (ResidualLosses).
      const int constrained = k % (N + 1) - 1;
      if (k % 2 == 1) {
        bank.UpdateWithLosses(absurd_output ? 1e13 : y, constrained, losses);
      } else {
        bank.Update(absurd_output ? 1e13 : y);
        bank.ResidualLosses(constrained, losses);
      }
      for (int l = 0; l < lanes; ++l) {
        // The same outcome and a-priori error on every sample.
        const auto& want = expected[static_cast<std::size_t>(l)];
        ASSERT_EQ(bank.result(l).outcome, want.outcome) << variant.name << " k " << k << " " << l;
        if (std::isnan(want.prediction_error)) {
          ASSERT_TRUE(std::isnan(bank.result(l).prediction_error));
        } else {
          ASSERT_EQ(bank.result(l).prediction_error, want.prediction_error) << variant.name;
        }
      }
      for (int l = 0; l < lanes; ++l) {
        const Rls<N>& ref = reference[static_cast<std::size_t>(l)];
        double want = ref.residual_sum_of_squares();
        if (constrained >= 0 && ref.theta()(constrained) < 0.0) {
          const double t = ref.theta()(constrained);
          const double pii = ref.CovarianceDiagonal(constrained);
          if (pii > 0.0) {
            want = want + t * t / pii;
            ++penalised;
          }
        }
        ASSERT_EQ(losses[static_cast<std::size_t>(l)], want)
            << variant.name << " k " << k << " lane " << l << " constrained " << constrained;
      }
      if (k % 97 == 0 || k == 1499) {
        ExpectLanesEqual<N>(bank, reference, variant.name + " at k = " + std::to_string(k));
      }
    }
    EXPECT_GT(penalised, 0) << variant.name << ": no lane's loss was that of a constrained fit";
  }
}

// Blocks are four lanes: 5, 6 and 1 lanes end in a part-filled block (padding lanes).
TEST(RlsBank, ThreeParametersEqualSeparateEstimatorsBitForBit) {
  RunAgainstSeparateEstimators<3>(5, RlsBankIsa::kBaseline);
  RunAgainstSeparateEstimators<3>(6, RlsBankIsa::kBaseline);
}

TEST(RlsBank, FourParametersEqualSeparateEstimatorsBitForBit) {
  RunAgainstSeparateEstimators<4>(24, RlsBankIsa::kBaseline);
  RunAgainstSeparateEstimators<4>(1, RlsBankIsa::kBaseline);
}

TEST(RlsBank, EightParametersEqualSeparateEstimatorsBitForBit) {
  RunAgainstSeparateEstimators<8>(7, RlsBankIsa::kBaseline);
}

// The AVX2 update (four lanes an operation) against the same references.  Not every CPU has
// AVX2: then the update cannot run here, and the test says so (skipped, not passed).
TEST(RlsBank, Avx2EqualsSeparateEstimatorsBitForBit) {
  if (__builtin_cpu_supports("avx2") == 0) {
    EXPECT_THROW(RlsBank<3>(RlsOptions{}, 1, RlsBankIsa::kAvx2), std::invalid_argument);
    GTEST_SKIP() << "this CPU has no AVX2: RlsBank's AVX2 update is not tested here";
  }
  RunAgainstSeparateEstimators<3>(5, RlsBankIsa::kAvx2);
  RunAgainstSeparateEstimators<4>(24, RlsBankIsa::kAvx2);
  RunAgainstSeparateEstimators<4>(1, RlsBankIsa::kAvx2);
  RunAgainstSeparateEstimators<8>(7, RlsBankIsa::kAvx2);
}

bool HasAvx512() {
  return __builtin_cpu_supports("avx2") != 0 && __builtin_cpu_supports("avx512f") != 0 &&
         __builtin_cpu_supports("avx512vl") != 0;
}

// The four-lane update compiled for AVX-512VL, whose FMA instructions the build keeps from
// contracting a * b + c (-ffp-contract=off): were a product and a sum fused, the lanes would
// round otherwise than Rls and this test would fail.  Skipped, saying so, where the CPU lacks it.
TEST(RlsBank, Avx512EqualsSeparateEstimatorsBitForBit) {
  if (!HasAvx512()) {
    EXPECT_THROW(RlsBank<3>(RlsOptions{}, 1, RlsBankIsa::kAvx512), std::invalid_argument);
    GTEST_SKIP() << "this CPU has no AVX-512F and AVX-512VL: RlsBank's AVX-512VL update is not "
                    "tested here";
  }
  RunAgainstSeparateEstimators<3>(5, RlsBankIsa::kAvx512);
  RunAgainstSeparateEstimators<4>(24, RlsBankIsa::kAvx512);
  RunAgainstSeparateEstimators<4>(1, RlsBankIsa::kAvx512);
  RunAgainstSeparateEstimators<8>(7, RlsBankIsa::kAvx512);
}

TEST(RlsBank, BestIsTheWidestRegisterFileTheCpuHas) {
  RlsOptions o;
  const RlsBankIsa want = HasAvx512()                           ? RlsBankIsa::kAvx512
                          : __builtin_cpu_supports("avx2") != 0 ? RlsBankIsa::kAvx2
                                                                : RlsBankIsa::kBaseline;
  EXPECT_EQ(RlsBank<4>(o, 3).isa(), want);
  EXPECT_EQ(RlsBank<4>(o, 3, RlsBankIsa::kBaseline).isa(), RlsBankIsa::kBaseline);
  if (__builtin_cpu_supports("avx2") != 0) {
    EXPECT_EQ(RlsBank<4>(o, 3, RlsBankIsa::kAvx2).isa(), RlsBankIsa::kAvx2);
  }
  // Innovation guards: one Rls per lane, no structure-of-arrays update, whatever was asked.
  o.huber = 2.0;
  EXPECT_EQ(RlsBank<4>(o, 3).isa(), RlsBankIsa::kBaseline);
}

TEST(RlsBank, TransformAndLaneRoundTrip) {
  RlsOptions o;
  o.forgetting = 0.99;
  RlsBank<3> bank(o, 3);
  std::vector<Rls<3>> reference(3, Rls<3>(o));
  for (int k = 0; k < 200; ++k) {
    for (int l = 0; l < 3; ++l) {
      const Eigen::Vector3d phi(std::sin(0.1 * k + l), 1.0, 0.01 * k);
      bank.regressors().col(l) = phi;
      reference[static_cast<std::size_t>(l)].Update(phi, 0.5 * std::sin(0.1 * k) + 0.2);
    }
    bank.Update(0.5 * std::sin(0.1 * k) + 0.2);
    if (k == 100) {
      Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
      t(1, 0) = 0.7;
      t(1, 2) = 3.0;
      for (int l = 0; l < 3; ++l) {
        const auto before = bank.result(l);
        bank.Transform(l, t);
        reference[static_cast<std::size_t>(l)].Transform(t);
        // A transform does not change what the last update did.
        EXPECT_EQ(bank.result(l).outcome, before.outcome);
        EXPECT_EQ(bank.result(l).prediction_error, before.prediction_error);
      }
    }
  }
  ExpectLanesEqual<3>(bank, reference, "after a transform");
  EXPECT_THROW(RlsBank<3>(o, 0), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
