// CSV records (drivers/csv/csv_table.h): CsvTable::Parse of the whole text, and CsvTable::Read of
// the same bytes a chunk at a time.  A rejected input must be a CsvError; an accepted table must
// have the properties Parse promises; and Read, whatever its chunk size, must give the same table
// or the same message (line numbers included) as Parse.
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <optional>
#include <string>

#include "drivers/csv/csv_table.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using canalid::drivers::CsvError;
using canalid::drivers::CsvTable;
using canalid::fuzz::Check;

// The table, or the message it was refused with.
struct Outcome {
  std::optional<CsvTable> table;
  std::string error;
};

template <class ReadTable>
Outcome Try(ReadTable read) {
  try {
    return {read(), {}};
  } catch (const CsvError& e) {
    return {std::nullopt, e.what()};
  }
}

// The bytes as a file only this process sees (a memfd), read back through its /proc path.
Outcome ReadInChunks(std::string_view text, std::size_t chunk_bytes, const std::string& name) {
  const int fd = ::memfd_create("csv_table_fuzz", MFD_CLOEXEC);
  Check(fd >= 0, "memfd_create works");
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    Check(n > 0, "the memfd takes the bytes");
    written += static_cast<std::size_t>(n);
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  Outcome outcome = Try([&] { return CsvTable::Read(path, chunk_bytes); });
  ::close(fd);
  // The messages name the file: the memfd's path stands for the name Parse was given.
  if (const auto at = outcome.error.find(path); at == 0)
    outcome.error.replace(0, path.size(), name);
  return outcome;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(canalid::fuzz::Text(data, size));
  const Outcome parsed = Try([&] { return CsvTable::Parse(text, "fuzz.csv"); });
  if (parsed.table) {
    const CsvTable& table = *parsed.table;
    Check(table.rows() >= 2, "a table has at least 2 rows");
    Check(!table.columns().empty() && table.columns().front() == "time_s", "time_s comes first");
    Check(std::isfinite(table.sample_time_s()) && table.sample_time_s() > 0.0,
          "the sample time is finite and positive");
    for (const std::string& name : table.columns()) {
      const auto column = table.Column(name);
      Check(column.size() == table.rows(), "every column has one value per row");
      Check(column.allFinite(), "every cell is finite");
    }
  }
  // A chunk size from the input's first byte: 1 to 64 bytes, so that lines are cut everywhere.
  const std::size_t chunk = size == 0 ? 1 : 1 + data[0] % 64;
  const Outcome read = ReadInChunks(text, chunk, "fuzz.csv");
  Check(read.table.has_value() == parsed.table.has_value(), "Read accepts what Parse accepts");
  Check(read.error == parsed.error, "Read refuses with Parse's message");
  if (parsed.table) {
    const CsvTable& a = *parsed.table;
    const CsvTable& b = *read.table;
    Check(a.columns() == b.columns() && a.rows() == b.rows(), "Read reads Parse's shape");
    for (const std::string& name : a.columns()) {
      Check(a.Column(name) == b.Column(name), "Read reads Parse's values");
    }
    Check(a.sample_time_s() == b.sample_time_s(), "Read reads Parse's sample time");
  }
  return 0;
}
