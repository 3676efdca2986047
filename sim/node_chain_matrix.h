#pragma once
#include <Eigen/Core>

namespace canalid::sim {

/// The Jacobian of a chain of N nodes with two unknowns each, u_j = (x[2j], x[2j+1]), and its
/// solution by a double sweep.  Row 0 involves u_0 only (the upstream boundary); rows 2j+1 and
/// 2j+2 involve u_j and u_{j+1} only (the two equations between neighbouring nodes: a Preissmann
/// segment, or a structure between pools); row 2N-1 involves u_{N-1} only (the downstream
/// boundary).  This is SaintVenantCanal's system with depths and flows interleaved.
///
/// The forward sweep carries one linear relation a h + b Q = c on the current node: with the
/// next two rows it makes three equations in u_j, and the combination w that eliminates u_j
/// (the cross product of their u_j columns, whose entries are the three 2 x 2 minors) leaves one
/// relation on u_{j+1}, rescaled to unit size.  The last row closes it on u_{N-1}; the backward
/// sweep solves each u_j from its relation and the link row whose minor with it is the larger.
/// No row exchanges and one choice per node: several times faster than banded elimination with
/// partial pivoting on this system, and as accurate on it (tests/sim/node_chain_matrix_test.cc,
/// against Eigen's dense LU, including a short-celled pool where solving from the link rows
/// alone is unstable).
/// Allocates only in the constructor.
class NodeChainMatrix final {
 public:
  /// The matrix of `nodes` nodes (2 nodes x 2 nodes), all zero.
  /// @throws std::invalid_argument unless nodes >= 1.
  explicit NodeChainMatrix(Eigen::Index nodes);

  Eigen::Index size() const { return 2 * nodes_; }
  /// Every coefficient to 0.
  void SetZero();
  /// Sets (row, col).  @throws std::out_of_range unless (row, col) is one of the structure's
  /// places (above).
  void Set(Eigen::Index row, Eigen::Index col, double value) { At(row, col) = value; }
  /// (row, col), 0 outside the structure.
  double Get(Eigen::Index row, Eigen::Index col) const;

  /// Solves A x = b in place (b becomes x); A is kept.  Returns false, with b unspecified, when
  /// A is singular (a relation or the last 2 x 2 system vanishes) or not finite.
  bool SolveInPlace(Eigen::VectorXd& b);

 private:
  /// (row, col)'s coefficient, or null outside the structure.
  double* Find(Eigen::Index row, Eigen::Index col) {
    const Eigen::Index n = size();
    if (row < 0 || row >= n || col < 0 || col >= n) return nullptr;
    // Row 0 and the last row first: with one node they are rows 0 and 1 of a 2 x 2.
    if (row == 0) return col > 1 ? nullptr : &first_[col];
    if (row == n - 1) return col < n - 2 ? nullptr : &last_[col - (n - 2)];
    const Eigen::Index link = (row - 1) / 2;
    const Eigen::Index offset = col - 2 * link;
    if (offset < 0 || offset > 3) return nullptr;
    return &links_(link, 4 * ((row - 1) % 2) + offset);
  }
  double& At(Eigen::Index row, Eigen::Index col) {
    double* const place = Find(row, col);
    if (place == nullptr) ThrowOutside(row, col);
    return *place;
  }
  [[noreturn]] void ThrowOutside(Eigen::Index row, Eigen::Index col) const;

  Eigen::Index nodes_;
  double first_[2] = {0.0, 0.0};  // row 0: u_0
  double last_[2] = {0.0, 0.0};   // row 2N-1: u_{N-1}
  // Link j (rows 2j+1, 2j+2): columns 0-3 of row 2j+1, then of row 2j+2, over u_j then u_{j+1}.
  Eigen::Matrix<double, Eigen::Dynamic, 8, Eigen::RowMajor> links_;
  // The forward sweep: relation (a, b, c) on each node; the minors w of each link.
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> relation_;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> minors_;
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> link_rhs_;  // b of each link's rows
};

}  // namespace canalid::sim
