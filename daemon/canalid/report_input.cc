#include "daemon/canalid/report_input.h"

#include "daemon/canalid/input_error.h"

namespace canalid::cli {

drivers::CsvTable LoadReportInput(const std::string& path) {
  try {
    return drivers::CsvTable::Read(path);
  } catch (const drivers::CsvError& e) {
    throw InputError(e.what());
  }
}

}  // namespace canalid::cli
