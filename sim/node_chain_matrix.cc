#include "sim/node_chain_matrix.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::sim {

namespace {

Eigen::Index CheckedNodes(Eigen::Index nodes) {
  if (nodes < 1) {
    throw std::invalid_argument("NodeChainMatrix: " + std::to_string(nodes) +
                                " nodes; at least 1 needed");
  }
  return nodes;
}

}  // namespace

NodeChainMatrix::NodeChainMatrix(Eigen::Index nodes)
    : nodes_(CheckedNodes(nodes)),
      links_(nodes_ - 1, 8),
      relation_(nodes_, 3),
      minors_(nodes_ - 1, 3),
      link_rhs_(nodes_ - 1, 2) {
  SetZero();
}

void NodeChainMatrix::SetZero() {
  first_[0] = first_[1] = last_[0] = last_[1] = 0.0;
  links_.setZero();
}

void NodeChainMatrix::ThrowOutside(Eigen::Index row, Eigen::Index col) const {
  throw std::out_of_range("NodeChainMatrix::Set(" + std::to_string(row) + ", " +
                          std::to_string(col) + "): not a place of a " + std::to_string(nodes_) +
                          "-node chain");
}

double NodeChainMatrix::Get(Eigen::Index row, Eigen::Index col) const {
  const double* const place = const_cast<NodeChainMatrix*>(this)->Find(row, col);
  return place == nullptr ? 0.0 : *place;
}

bool NodeChainMatrix::SolveInPlace(Eigen::VectorXd& b) {
  // Forward: the relation on u_0 is row 0; each link turns the relation on u_j into one on
  // u_{j+1}.
  relation_.row(0) << first_[0], first_[1], b(0);
  for (Eigen::Index j = 0; j + 1 < nodes_; ++j) {
    const double* const l = links_.row(j).data();  // l[0..3]: row 2j+1, l[4..7]: row 2j+2
    const double a = relation_(j, 0), bb = relation_(j, 1), c = relation_(j, 2);
    // The u_j columns of the three equations, (a, l0, l4) and (bb, l1, l5); their cross product
    // w annihilates both: w0 = minor of rows (1, 2), w1 = -minor of (0, 2), w2 = minor of (0, 1).
    const double w0 = l[0] * l[5] - l[4] * l[1];
    const double w1 = l[4] * bb - a * l[5];
    const double w2 = a * l[1] - l[0] * bb;
    minors_.row(j) << w0, w1, w2;
    const double next_a = w1 * l[2] + w2 * l[6];
    const double next_b = w1 * l[3] + w2 * l[7];
    const double r1 = b(2 * j + 1), r2 = b(2 * j + 2);
    link_rhs_.row(j) << r1, r2;  // b(2j+2) becomes h_{j+1} in the backward sweep
    const double next_c = w0 * c + w1 * r1 + w2 * r2;
    const double scale = std::max(std::abs(next_a), std::abs(next_b));
    if (!(scale > 0.0) || !std::isfinite(scale)) return false;
    const double inverse = 1.0 / scale;
    relation_.row(j + 1) << next_a * inverse, next_b * inverse, next_c * inverse;
  }
  // The relation on u_{N-1} and the last row.
  const Eigen::Index n = size();
  const Eigen::Index end = nodes_ - 1;
  const double a = relation_(end, 0), bb = relation_(end, 1), c = relation_(end, 2);
  const double det = a * last_[1] - bb * last_[0];
  if (!(std::abs(det) > 0.0) || !std::isfinite(det)) return false;
  const double f = b(n - 1);
  b(n - 2) = (c * last_[1] - bb * f) / det;
  b(n - 1) = (a * f - c * last_[0]) / det;
  // Backward: u_j from the relation on it and the link row whose minor with the relation is the
  // larger.  The relation carries the upstream end's information; the two link rows alone would
  // march the scheme from downstream to upstream, which amplifies the rounding (by about 1e3 per
  // ten nodes on a short-celled pool at a small step).
  for (Eigen::Index j = nodes_ - 2; j >= 0; --j) {
    const double* const l = links_.row(j).data();
    const double h1 = b(2 * j + 2), q1 = b(2 * j + 3);
    // The three equations in u_j: coefficients (p, q), right-hand side r.
    const double p[3] = {relation_(j, 0), l[0], l[4]};
    const double q[3] = {relation_(j, 1), l[1], l[5]};
    const double r[3] = {relation_(j, 2), link_rhs_(j, 0) - l[2] * h1 - l[3] * q1,
                         link_rhs_(j, 1) - l[6] * h1 - l[7] * q1};
    // The relation (equation 0) and the link row whose minor with it is the larger.
    // (w1 is the minor of equations 0 and 2, w2 that of 0 and 1.)
    const int k = std::abs(minors_(j, 1)) >= std::abs(minors_(j, 2)) ? 2 : 1;
    const int i = 0;
    const double d = p[i] * q[k] - p[k] * q[i];
    if (!(std::abs(d) > 0.0)) return false;
    b(2 * j) = (r[i] * q[k] - r[k] * q[i]) / d;
    b(2 * j + 1) = (p[i] * r[k] - p[k] * r[i]) / d;
  }
  return true;
}

}  // namespace canalid::sim
