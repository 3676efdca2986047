#include "sim/banded_solver.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace canalid::sim {

BandedMatrix::BandedMatrix(Eigen::Index n, int kl, int ku)
    : n_(n), kl_(kl), ku_(ku), a_(n, 2 * kl + ku + 1) {
  a_.setZero();
}

void BandedMatrix::Set(Eigen::Index row, Eigen::Index col, double value) {
  if (row < 0 || row >= n_ || col < 0 || col >= n_ || col < row - kl_ || col > row + ku_) {
    throw std::out_of_range("BandedMatrix::Set(" + std::to_string(row) + ", " +
                            std::to_string(col) + "): outside the band");
  }
  At(row, col) = value;
}

double BandedMatrix::Get(Eigen::Index row, Eigen::Index col) const {
  if (row < 0 || row >= n_ || col < 0 || col >= n_ || col < row - kl_ || col > row + ku_ + kl_) {
    return 0.0;
  }
  return a_(row, col - row + kl_);
}

bool BandedMatrix::SolveInPlace(Eigen::VectorXd& b) {
  const Eigen::Index width = ku_ + kl_;  // U's upper bandwidth after the exchanges
  for (Eigen::Index i = 0; i < n_; ++i) {
    const Eigen::Index last_row = std::min(n_ - 1, i + kl_);
    const Eigen::Index last_col = std::min(n_ - 1, i + width);
    // Partial pivoting: the largest |a(r, i)| of the rows that reach column i.
    Eigen::Index pivot = i;
    double largest = std::abs(At(i, i));
    for (Eigen::Index r = i + 1; r <= last_row; ++r) {
      if (std::abs(At(r, i)) > largest) {
        largest = std::abs(At(r, i));
        pivot = r;
      }
    }
    if (largest == 0.0) return false;
    if (pivot != i) {
      // Both rows are zero left of column i; row i's entries end at last_col, row pivot's too.
      for (Eigen::Index c = i; c <= last_col; ++c) std::swap(At(i, c), At(pivot, c));
      std::swap(b(i), b(pivot));
    }
    const double diagonal = At(i, i);
    for (Eigen::Index r = i + 1; r <= last_row; ++r) {
      const double factor = At(r, i) / diagonal;
      if (factor == 0.0) continue;
      At(r, i) = 0.0;
      for (Eigen::Index c = i + 1; c <= last_col; ++c) At(r, c) -= factor * At(i, c);
      b(r) -= factor * b(i);
    }
  }
  for (Eigen::Index i = n_ - 1; i >= 0; --i) {
    const Eigen::Index last_col = std::min(n_ - 1, i + width);
    double sum = b(i);
    for (Eigen::Index c = i + 1; c <= last_col; ++c) sum -= At(i, c) * b(c);
    b(i) = sum / At(i, i);
  }
  return true;
}

}  // namespace canalid::sim
