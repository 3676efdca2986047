// CSV records (drivers/csv/csv_table.h): CsvTable::Parse, the reader behind CsvTable::Read.  A
// rejected input must be a CsvError; an accepted table must have the properties Parse promises.
#include <cmath>
#include <string>

#include "drivers/csv/csv_table.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using canalid::fuzz::Check;
  try {
    const auto table =
        canalid::drivers::CsvTable::Parse(std::string(canalid::fuzz::Text(data, size)), "fuzz.csv");
    Check(table.rows() >= 2, "a table has at least 2 rows");
    Check(!table.columns().empty() && table.columns().front() == "time_s", "time_s comes first");
    Check(std::isfinite(table.sample_time_s()) && table.sample_time_s() > 0.0,
          "the sample time is finite and positive");
    for (const std::string& name : table.columns()) {
      const Eigen::VectorXd column = table.Column(name);
      Check(column.size() == table.rows(), "every column has one value per row");
      Check(column.allFinite(), "every cell is finite");
    }
  } catch (const canalid::drivers::CsvError&) {
    // A rejected record, with a message: expected.
  }
  return 0;
}
