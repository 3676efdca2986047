// NodeChainMatrix against Eigen's dense LU with partial pivoting on the same matrices.
#include "sim/node_chain_matrix.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <limits>
#include <random>
#include <stdexcept>

namespace canalid::sim {
namespace {

// Every place of a chain of `nodes` nodes: row 0 on u_0, rows 2j+1 and 2j+2 on u_j and u_{j+1},
// the last row on u_{N-1}.
template <typename Visit>
void ForEachPlace(Eigen::Index nodes, Visit visit) {
  const Eigen::Index n = 2 * nodes;
  visit(0, 0);
  visit(0, 1);
  for (Eigen::Index j = 0; j + 1 < nodes; ++j) {
    for (Eigen::Index r = 2 * j + 1; r <= 2 * j + 2; ++r) {
      for (Eigen::Index c = 2 * j; c <= 2 * j + 3; ++c) visit(r, c);
    }
  }
  visit(n - 1, n - 2);
  visit(n - 1, n - 1);
}

enum class Shape {
  kRandom,
  // Zeros where SaintVenantCanal's system has them: a flow boundary (row 0 on Q_0 only), the
  // structure rows (no h_{j+1} in the first, no Q_j in the second), a pump at the end (the last
  // row on Q only).
  kCanalZeros,
};

void RandomChain(Eigen::Index nodes, Shape shape, std::mt19937_64& rng, NodeChainMatrix& chain,
                 Eigen::MatrixXd& dense) {
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  dense.setZero(2 * nodes, 2 * nodes);
  chain.SetZero();
  ForEachPlace(nodes, [&](Eigen::Index r, Eigen::Index c) {
    double v = value(rng);
    if (shape == Shape::kCanalZeros) {
      const bool structure_link = r > 0 && r < 2 * nodes - 1 && ((r - 1) / 2) % 3 == 2;
      if ((r == 0 && c == 0) || (r == 2 * nodes - 1 && c == 2 * nodes - 2)) v = 0.0;
      if (structure_link && r % 2 == 1 && c == r + 1) v = 0.0;  // no h_{j+1}
      if (structure_link && r % 2 == 0 && c == r - 1) v = 0.0;  // no Q_j
    }
    dense(r, c) = v;
    chain.Set(r, c, v);
  });
}

TEST(NodeChainMatrix, SolvesAsDenseLuWithPartialPivoting) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const Eigen::Index nodes : {1, 2, 3, 8, 71, 144}) {
    for (const Shape shape : {Shape::kRandom, Shape::kCanalZeros}) {
      // One node with both ends on Q alone is singular (a canal has two nodes or more a pool).
      if (shape == Shape::kCanalZeros && nodes == 1) continue;
      for (int trial = 0; trial < (nodes > 50 ? 3 : 20); ++trial) {
        NodeChainMatrix chain(nodes);
        Eigen::MatrixXd dense;
        RandomChain(nodes, shape, rng, chain, dense);
        for (Eigen::Index r = 0; r < 2 * nodes; ++r) {
          for (Eigen::Index c = 0; c < 2 * nodes; ++c) {
            ASSERT_EQ(chain.Get(r, c), dense(r, c)) << r << " " << c;
          }
        }
        Eigen::VectorXd b(2 * nodes);
        for (Eigen::Index i = 0; i < b.size(); ++i) b(i) = normal(rng);
        const Eigen::VectorXd expected = dense.partialPivLu().solve(b);
        Eigen::VectorXd x = b;
        ASSERT_TRUE(chain.SolveInPlace(x)) << nodes;
        // Both backward stable: the same x up to the condition number times the rounding, and
        // a residual of the order of the rounding of A x.
        const double condition = dense.norm() * dense.inverse().norm();
        EXPECT_LT((x - expected).norm(), 1e-13 * condition * expected.norm())
            << nodes << " nodes, condition " << condition;
        EXPECT_LT((dense * x - b).norm(), 1e-12 * dense.norm() * x.norm()) << nodes;
        // The matrix is kept: a second solve gives the same x.
        Eigen::VectorXd again = b;
        ASSERT_TRUE(chain.SolveInPlace(again));
        EXPECT_EQ(again, x);
      }
    }
  }
}

// The Preissmann Jacobian of a short-celled pool at a small step (ASCE canal 1 pool 1, 61 nodes,
// dx 13.5 m, dt 1.35 s, a flow boundary and a pump at the end), each coefficient moved by up to
// 5 %.  Condition about 550; solving each node from the two link rows alone (marching
// downstream-to-upstream through the scheme) amplifies the rounding a thousandfold per ten
// nodes here and makes Newton diverge, so the backward sweep must use the relation.
TEST(NodeChainMatrix, AShortCelledPreissmannChainIsSolvedStably) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(0.95, 1.05);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::Index nodes = 61;
  NodeChainMatrix chain(nodes);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(2 * nodes, 2 * nodes);
  const auto set = [&](Eigen::Index r, Eigen::Index c, double v) {
    dense(r, c) = v;
    chain.Set(r, c, v);
  };
  set(0, 1, 1.0);  // Q_0 given
  for (Eigen::Index j = 0; j + 1 < nodes; ++j) {
    const double continuity[4] = {9.6, -0.36, 9.6, 0.36};
    const double momentum[4] = {-3.4, 2.05, 3.5, 3.93};
    for (Eigen::Index c = 0; c < 4; ++c) {
      set(2 * j + 1, 2 * j + c, continuity[c] * jitter(rng));
      set(2 * j + 2, 2 * j + c, momentum[c] * jitter(rng));
    }
  }
  set(2 * nodes - 1, 2 * nodes - 1, 1.0);  // the pump: Q_{N-1} given
  Eigen::VectorXd b(2 * nodes);
  for (Eigen::Index i = 0; i < b.size(); ++i) b(i) = normal(rng);
  const Eigen::VectorXd expected = dense.partialPivLu().solve(b);
  Eigen::VectorXd x = b;
  ASSERT_TRUE(chain.SolveInPlace(x));
  const double condition = dense.norm() * dense.inverse().norm();
  EXPECT_LT(condition, 1e4);
  EXPECT_LT((x - expected).norm(), 1e-13 * condition * expected.norm()) << condition;
  EXPECT_LT((dense * x - b).norm(), 1e-12 * dense.norm() * x.norm());
}

TEST(NodeChainMatrix, ASingularChainIsReported) {
  // Link 0's two rows are proportional on every column: rank 3 of 4.
  NodeChainMatrix chain(2);
  chain.Set(0, 0, 1.0);
  chain.Set(0, 1, 1.0);
  for (Eigen::Index c = 0; c < 4; ++c) {
    chain.Set(1, c, 1.0 + static_cast<double>(c));
    chain.Set(2, c, 2.0 * (1.0 + static_cast<double>(c)));
  }
  chain.Set(3, 2, 1.0);
  chain.Set(3, 3, -1.0);
  Eigen::VectorXd b = Eigen::VectorXd::Ones(4);
  EXPECT_FALSE(chain.SolveInPlace(b));
  // A last row that repeats the relation on the last node.
  NodeChainMatrix one(1);
  one.Set(0, 0, 1.0);
  one.Set(0, 1, 2.0);
  one.Set(1, 0, -2.0);
  one.Set(1, 1, -4.0);
  Eigen::VectorXd c = Eigen::VectorXd::Ones(2);
  EXPECT_FALSE(one.SolveInPlace(c));
  // Not finite.
  one.Set(1, 1, std::numeric_limits<double>::quiet_NaN());
  EXPECT_FALSE(one.SolveInPlace(c));
}

TEST(NodeChainMatrix, PlacesOutsideTheChainAreRefused) {
  NodeChainMatrix chain(3);  // 6 x 6
  EXPECT_THROW(chain.Set(0, 2, 1.0), std::out_of_range);
  EXPECT_THROW(chain.Set(1, 4, 1.0), std::out_of_range);
  EXPECT_THROW(chain.Set(3, 1, 1.0), std::out_of_range);
  EXPECT_THROW(chain.Set(5, 3, 1.0), std::out_of_range);
  EXPECT_THROW(chain.Set(6, 5, 1.0), std::out_of_range);
  EXPECT_THROW(chain.Set(-1, 0, 1.0), std::out_of_range);
  EXPECT_NO_THROW(chain.Set(3, 5, 1.0));
  EXPECT_EQ(chain.Get(0, 5), 0.0);
  EXPECT_THROW(NodeChainMatrix(0), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::sim
