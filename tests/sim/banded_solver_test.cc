// BandedMatrix against Eigen's dense LU with partial pivoting on the same matrices.
#include "sim/banded_solver.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>
#include <stdexcept>

namespace canalid::sim {
namespace {

struct Case {
  Eigen::Index n;
  int kl;
  int ku;
};

// A random band matrix in both forms.  zero_diagonal: every other diagonal entry is 0, so the
// solve must exchange rows (as SaintVenantCanal's first row, a flow boundary, does).
void RandomBand(const Case& c, bool zero_diagonal, std::mt19937_64& rng, BandedMatrix& band,
                Eigen::MatrixXd& dense) {
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  dense.setZero(c.n, c.n);
  band.SetZero();
  for (Eigen::Index r = 0; r < c.n; ++r) {
    for (Eigen::Index col = std::max<Eigen::Index>(0, r - c.kl);
         col <= std::min<Eigen::Index>(c.n - 1, r + c.ku); ++col) {
      const double v = (zero_diagonal && col == r && r % 2 == 0) ? 0.0 : value(rng);
      dense(r, col) = v;
      band.Set(r, col, v);
    }
  }
}

TEST(BandedMatrix, SolvesAsDenseLuWithPartialPivoting) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const Case c : {Case{1, 0, 0}, Case{7, 2, 2}, Case{60, 2, 2}, Case{40, 1, 3}, Case{40, 3, 1},
                       Case{33, 0, 2}}) {
    for (const bool zero_diagonal : {false, true}) {
      if (zero_diagonal && c.kl == 0) continue;  // no row below to exchange with: singular
      BandedMatrix band(c.n, c.kl, c.ku);
      Eigen::MatrixXd dense;
      RandomBand(c, zero_diagonal, rng, band, dense);
      for (Eigen::Index r = 0; r < c.n; ++r) {
        for (Eigen::Index col = 0; col < c.n; ++col) {
          ASSERT_EQ(band.Get(r, col), dense(r, col)) << r << " " << col;
        }
      }
      Eigen::VectorXd b(c.n);
      for (Eigen::Index i = 0; i < c.n; ++i) b(i) = normal(rng);
      const Eigen::VectorXd expected = dense.partialPivLu().solve(b);
      Eigen::VectorXd x = b;
      ASSERT_TRUE(band.SolveInPlace(x)) << c.n << " " << c.kl << " " << c.ku;
      // Both are backward stable: the same x up to the condition number times the rounding,
      // and a residual of the order of the rounding of A x.
      const double condition = dense.norm() * dense.inverse().norm();
      EXPECT_LT((x - expected).norm(), 1e-14 * condition * expected.norm())
          << c.n << " " << c.kl << " " << c.ku << " " << zero_diagonal;
      EXPECT_LT((dense * x - b).norm(), 1e-13 * dense.norm() * x.norm());
    }
  }
}

TEST(BandedMatrix, ASingularMatrixIsReportedAndOutsideTheBandIsRefused) {
  BandedMatrix band(3, 1, 1);
  band.Set(0, 0, 1.0);
  band.Set(0, 1, 2.0);
  band.Set(1, 0, 2.0);
  band.Set(1, 1, 4.0);  // row 1 = 2 x row 0
  band.Set(2, 2, 1.0);
  Eigen::VectorXd b = Eigen::VectorXd::Ones(3);
  EXPECT_FALSE(band.SolveInPlace(b));
  EXPECT_THROW(band.Set(0, 2, 1.0), std::out_of_range);
  EXPECT_THROW(band.Set(2, 0, 1.0), std::out_of_range);
  EXPECT_THROW(band.Set(3, 3, 1.0), std::out_of_range);
}

}  // namespace
}  // namespace canalid::sim
