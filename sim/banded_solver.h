#pragma once
#include <Eigen/Core>

namespace canalid::sim {

/// A square band matrix with kl sub- and ku super-diagonals, and its solution by Gaussian
/// elimination with partial pivoting (LAPACK's dgbsv algorithm).  Row r is stored with room for
/// the fill the row exchanges bring: columns r - kl .. r + ku + kl.  The Preissmann system of
/// SaintVenantCanal is such a matrix (kl = ku = 2 with depths and flows interleaved); a band
/// solve costs O(n kl (kl + ku)) where a general sparse LU spent most of a simulation step in
/// its symbolic bookkeeping.  Allocates only in the constructor.
class BandedMatrix final {
 public:
  /// @pre n >= 1, kl >= 0, ku >= 0.
  BandedMatrix(Eigen::Index n, int kl, int ku);

  Eigen::Index size() const { return n_; }
  /// Every stored coefficient to 0.
  void SetZero() { a_.setZero(); }
  /// Sets (row, col).  @pre |col - row| inside the band (checked: std::out_of_range).
  void Set(Eigen::Index row, Eigen::Index col, double value) {
    if (row < 0 || row >= n_ || col < 0 || col >= n_ || col < row - kl_ || col > row + ku_) {
      ThrowOutsideBand(row, col);
    }
    At(row, col) = value;
  }
  double Get(Eigen::Index row, Eigen::Index col) const;

  /// Solves A x = b in place (b becomes x) and destroys A (it holds the U factor after).
  /// Returns false, with b unspecified, when a pivot is exactly zero (A singular).
  bool SolveInPlace(Eigen::VectorXd& b);

 private:
  [[noreturn]] static void ThrowOutsideBand(Eigen::Index row, Eigen::Index col);
  double& At(Eigen::Index row, Eigen::Index col) { return a_(row, col - row + kl_); }
  /// Row r addressed by column: RowByColumn(r)[c] is (r, c) for c in r - kl .. r + ku + kl.
  double* RowByColumn(Eigen::Index r) { return a_.data() + r * a_.cols() + kl_ - r; }
  Eigen::Index n_;
  int kl_;
  int ku_;
  // n x (2 kl + ku + 1), row-major: row r's columns r - kl .. r + ku + kl.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> a_;
};

}  // namespace canalid::sim
