#pragma once
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace canalid::cli {

/// The trajectory file of `canalid identify --online --trace`: time_s first, then the given
/// columns, 17 significant digits, one row per sample with a valid estimate.  An empty path
/// writes nothing.  @throws InputError naming --trace when the file cannot be opened or written.
class TraceWriter final {
 public:
  TraceWriter(const std::string& path, const std::vector<std::string>& names);
  bool enabled() const { return file_ != nullptr; }
  void Row(double time_s, const double* values, std::size_t count);
  void Close();

 private:
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::string path_;
  std::unique_ptr<std::FILE, Closer> file_;
};

}  // namespace canalid::cli
