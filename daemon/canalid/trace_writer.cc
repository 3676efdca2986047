#include "daemon/canalid/trace_writer.h"

#include "daemon/canalid/input_error.h"

namespace canalid::cli {

TraceWriter::TraceWriter(const std::string& path, const std::vector<std::string>& names)
    : path_(path) {
  if (path.empty()) return;
  file_.reset(std::fopen(path.c_str(), "w"));
  if (!file_) throw InputError("--trace " + path + ": cannot open for writing");
  std::fputs("time_s", file_.get());
  for (const auto& name : names) std::fprintf(file_.get(), ",%s", name.c_str());
  std::fputc('\n', file_.get());
}

void TraceWriter::Row(double time_s, const double* values, std::size_t count) {
  std::fprintf(file_.get(), "%.17g", time_s);
  for (std::size_t i = 0; i < count; ++i) std::fprintf(file_.get(), ",%.17g", values[i]);
  std::fputc('\n', file_.get());
}

void TraceWriter::Close() {
  if (file_ && std::fclose(file_.release()) != 0) {
    throw InputError("--trace " + path_ + ": cannot write");
  }
}

}  // namespace canalid::cli
