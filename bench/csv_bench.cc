// drivers::CsvTable::Read of the CSV file named by $CANALID_CSV_BENCH_INPUT
// (bench/compare_csv_read.sh writes one and times numpy.loadtxt on the same file): the reader every
// `canalid` command uses.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "drivers/csv/csv_table.h"

namespace {

void BM_CsvTableRead(benchmark::State& state) {
  // NOLINTNEXTLINE(concurrency-mt-unsafe): read before any thread of the benchmark
  const char* path = std::getenv("CANALID_CSV_BENCH_INPUT");
  if (path == nullptr) {
    state.SkipWithError("set CANALID_CSV_BENCH_INPUT to a CSV file (bench/compare_csv_read.sh)");
    return;
  }
  const auto bytes = static_cast<std::int64_t>(std::filesystem::file_size(path));
  std::int64_t rows = 0;
  for (auto _ : state) {
    const canalid::drivers::CsvTable table = canalid::drivers::CsvTable::Read(path);
    rows += table.rows();
    benchmark::DoNotOptimize(table.sample_time_s());
  }
  state.SetBytesProcessed(bytes * static_cast<std::int64_t>(state.iterations()));
  state.counters["rows_per_s"] =
      benchmark::Counter(static_cast<double>(rows), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_CsvTableRead)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
