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

void BandedMatrix::ThrowOutsideBand(Eigen::Index row, Eigen::Index col) {
  throw std::out_of_range("BandedMatrix::Set(" + std::to_string(row) + ", " + std::to_string(col) +
                          "): outside the band");
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
    double largest = std::abs(RowByColumn(i)[i]);
    for (Eigen::Index r = i + 1; r <= last_row; ++r) {
      if (std::abs(RowByColumn(r)[i]) > largest) {
        largest = std::abs(RowByColumn(r)[i]);
        pivot = r;
      }
    }
    if (largest == 0.0) return false;
    double* const row_i = RowByColumn(i);
    if (pivot != i) {
      // Both rows are zero left of column i; row i's entries end at last_col, row pivot's too.
      double* const row_p = RowByColumn(pivot);
      for (Eigen::Index c = i; c <= last_col; ++c) std::swap(row_i[c], row_p[c]);
      std::swap(b(i), b(pivot));
    }
    const double diagonal = row_i[i];
    for (Eigen::Index r = i + 1; r <= last_row; ++r) {
      double* const row_r = RowByColumn(r);
      const double factor = row_r[i] / diagonal;
      if (factor == 0.0) continue;
      row_r[i] = 0.0;
      for (Eigen::Index c = i + 1; c <= last_col; ++c) row_r[c] -= factor * row_i[c];
      b(r) -= factor * b(i);
    }
  }
  for (Eigen::Index i = n_ - 1; i >= 0; --i) {
    const Eigen::Index last_col = std::min(n_ - 1, i + width);
    const double* const row_i = RowByColumn(i);
    double sum = b(i);
    for (Eigen::Index c = i + 1; c <= last_col; ++c) sum -= row_i[c] * b(c);
    b(i) = sum / row_i[i];
  }
  return true;
}

}  // namespace canalid::sim
