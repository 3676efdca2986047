#pragma once
#include <stdexcept>

namespace canalid::cli {

/// Bad input named precisely (file, row, column, option): `canalid` prints it and exits 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace canalid::cli
