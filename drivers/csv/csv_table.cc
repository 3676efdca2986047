#include "drivers/csv/csv_table.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <string_view>
#include <unordered_set>

#include "core/system/errno_text.h"

namespace canalid::drivers {
namespace {

std::string_view TrimView(std::string_view s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return {};
  const auto end = s.find_last_not_of(" \t\r");
  return s.substr(begin, end - begin + 1);
}

std::vector<std::string> SplitCells(std::string_view line) {
  std::vector<std::string> cells;
  while (true) {
    const auto comma = line.find(',');
    cells.emplace_back(TrimView(line.substr(0, comma)));
    if (comma == std::string_view::npos) break;
    line.remove_prefix(comma + 1);
  }
  return cells;
}

// The newlines in `text`, 16 bytes per step with GCC's vector extensions (SSE2, the x86-64
// baseline): counting them with a memchr call per line costs a call per line, and a plain loop
// over the bytes is not vectorised at -O2.
std::size_t CountNewlines(std::string_view text) {
  using Bytes = unsigned char __attribute__((vector_size(16)));
  constexpr std::ptrdiff_t kWidth = sizeof(Bytes);
  constexpr std::ptrdiff_t kMaxSteps = 255;  // before a lane's 8-bit count could wrap
  const char* p = text.data();
  const char* const end = text.data() + text.size();
  std::size_t count = 0;
  while (end - p >= kWidth) {
    Bytes counts{};
    const char* const stop = p + kWidth * std::min((end - p) / kWidth, kMaxSteps);
    for (; p < stop; p += kWidth) {
      Bytes chunk;
      std::memcpy(&chunk, p, sizeof chunk);
      // A match is -1 (all bits set), 255 as an unsigned byte: subtracting it adds 1.
      counts -= __builtin_convertvector(chunk == '\n', Bytes);
    }
    for (int lane = 0; lane < kWidth; ++lane) count += counts[lane];
  }
  for (; p < end; ++p) count += *p == '\n' ? 1 : 0;
  return count;
}

// The lines of a text, without copying: Next() gives each one (without its '\n') and counts them.
class Lines {
 public:
  explicit Lines(std::string_view text) : rest_(text) {}
  bool Next(std::string_view& line) {
    if (done_) return false;
    ++number_;
    const void* nl = std::memchr(rest_.data(), '\n', rest_.size());
    if (nl == nullptr) {
      line = rest_;
      done_ = true;
      return true;
    }
    const auto length = static_cast<std::size_t>(static_cast<const char*>(nl) - rest_.data());
    line = rest_.substr(0, length);
    rest_.remove_prefix(length + 1);
    return true;
  }
  std::size_t number() const { return number_; }
  /// The most lines Next can still return that are not blank: the newlines left, plus an
  /// unterminated last line.
  std::size_t MaxLinesLeft() const {
    if (done_ || rest_.empty()) return 0;
    return CountNewlines(rest_) + (rest_.back() == '\n' ? 0 : 1);
  }
  /// What Next has not returned yet (empty once it returned the last line).
  std::string_view rest() const { return done_ ? std::string_view() : rest_; }
  /// Takes the next line as read by the caller: `length` bytes of rest() and the '\n' after
  /// them (or the end of the text).  @pre rest()[length] is '\n', or length == rest().size().
  void Consume(std::size_t length) {
    ++number_;
    if (length >= rest_.size()) {
      done_ = true;
    } else {
      rest_.remove_prefix(length + 1);
    }
  }

 private:
  std::string_view rest_;
  std::size_t number_ = 0;
  bool done_ = false;
};

[[noreturn]] void Fail(const std::string& source, std::size_t line, const std::string& what);

// Why cell `c` (starting at `cell_start` in `line`) of a row of `width` cells was refused: the
// row has another number of cells, or the cell is not one finite number.
[[noreturn]] void CellProblem(const std::string& source, std::size_t line_number,
                              std::string_view line, const char* cell_start,
                              const std::vector<std::string>& columns, std::size_t c,
                              std::size_t width) {
  const auto found = static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
  if (found != width) {
    Fail(source, line_number,
         "expected " + std::to_string(width) + " cells, found " + std::to_string(found));
  }
  std::string_view rest = line.substr(static_cast<std::size_t>(cell_start - line.data()));
  const std::string cell(TrimView(rest.substr(0, rest.find(','))));
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), v);
  if (cell.empty() || ec != std::errc() || ptr != cell.data() + cell.size()) {
    Fail(source, line_number, "column '" + columns[c] + "': '" + cell + "' is not a number");
  }
  Fail(source, line_number, "column '" + columns[c] + "': '" + cell + "' is not finite");
}

[[noreturn]] void Fail(const std::string& source, std::size_t line, const std::string& what) {
  throw CsvError(source + ":" + std::to_string(line) + ": " + what);
}

std::string CellText(double v) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, end);
}

// What is wrong with a header (empty when nothing): time_s first, every name present and unique.
std::string HeaderProblem(const std::vector<std::string>& columns) {
  if (columns.empty() || columns.front() != "time_s") {
    return "the first column must be 'time_s' (found '" +
           (columns.empty() ? std::string() : columns.front()) + "')";
  }
  std::unordered_set<std::string> seen;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    if (columns[c].empty()) return "column " + std::to_string(c + 1) + " has no name";
    if (!seen.insert(columns[c]).second) return "column '" + columns[c] + "' appears twice";
  }
  return {};
}

// What is wrong with time t of row `rows` (1-based, >= 2) after t_prev, the first time being t0
// (empty when nothing).  Row 2 sets the sample time.
std::string TimeProblem(double t0, double t_prev, double t, std::size_t rows,
                        double& sample_time_s) {
  if (!(t > t_prev)) {
    return "time_s " + CellText(t) + " does not increase (previous " + CellText(t_prev) + ")";
  }
  if (rows == 2) {
    sample_time_s = t - t_prev;
    return {};
  }
  const double expected = t0 + static_cast<double>(rows - 1) * sample_time_s;
  if (std::abs(t - expected) > 1e-6 * sample_time_s * static_cast<double>(rows) + 1e-9) {
    return "time_s " + CellText(t) + " breaks uniform sampling (expected " + CellText(expected) +
           ", sample time " + CellText(sample_time_s) + " s)";
  }
  return {};
}

}  // namespace

bool CsvTable::HasColumn(const std::string& name) const {
  for (const auto& c : columns_) {
    if (c == name) return true;
  }
  return false;
}

Eigen::VectorXd CsvTable::Column(const std::string& name) const {
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (columns_[i] == name) return data_.col(static_cast<Eigen::Index>(i));
  }
  std::string known;
  for (const auto& c : columns_) known += (known.empty() ? "" : ", ") + c;
  throw CsvError(source_ + ": no column '" + name + "' (columns: " + known + ")");
}

CsvTable CsvTable::Read(const std::string& path) {
  struct Fd {
    int fd;
    ~Fd() {
      if (fd >= 0) ::close(fd);
    }
  } file{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (file.fd < 0) throw CsvError(path + ": cannot open file");
  struct stat st {};
  if (::fstat(file.fd, &st) == 0 && S_ISDIR(st.st_mode)) {
    throw CsvError(path + ": is a directory, not a CSV file");
  }
  // One buffer, read from the descriptor already open (a pipe cannot be opened twice), sized
  // from a regular file's length and grown for anything else; not zero-filled first. (Mapping
  // the file instead saves the copy but dies of SIGBUS when another process shrinks it.)
  std::size_t capacity = S_ISREG(st.st_mode) && st.st_size > 0
                             ? static_cast<std::size_t>(st.st_size) + 1
                             : std::size_t{65536};
  auto buffer = std::make_unique_for_overwrite<char[]>(capacity);
  std::size_t size = 0;
  while (true) {
    if (size == capacity) {
      auto bigger = std::make_unique_for_overwrite<char[]>(2 * capacity);
      std::memcpy(bigger.get(), buffer.get(), size);
      buffer = std::move(bigger);
      capacity *= 2;
    }
    const ssize_t n = ::read(file.fd, buffer.get() + size, capacity - size);
    if (n > 0) {
      size += static_cast<std::size_t>(n);
    } else if (n == 0) {
      break;
    } else if (errno != EINTR) {
      throw CsvError(path + ": cannot read file (" + core::ErrnoText(errno) + ")");
    }
  }
  return Parse(std::string_view(buffer.get(), size), path);
}

CsvTable CsvTable::Parse(std::string_view text, const std::string& name) {
  CsvTable table;
  table.source_ = name;
  Lines lines(text);
  std::string_view line;
  // Header: the first line that is not blank.
  bool header = false;
  while (lines.Next(line)) {
    if (!TrimView(line).empty()) {
      header = true;
      break;
    }
  }
  if (!header) throw CsvError(name + ": empty file (no header row)");
  table.columns_ = SplitCells(line);
  if (const std::string problem = HeaderProblem(table.columns_); !problem.empty()) {
    Fail(name, lines.number(), problem);
  }
  const std::size_t width = table.columns_.size();
  // Room for every remaining line's values at once (a row per line is the most there can be);
  // the values go straight into their columns (column-major, as the table keeps them), and the
  // matrix becomes the table's without a copy unless blank lines left rows unused.
  const std::size_t capacity = lines.MaxLinesLeft();
  Eigen::MatrixXd values(static_cast<Eigen::Index>(capacity), static_cast<Eigen::Index>(width));
  std::size_t rows = 0;
  // Time checks as rows arrive, so the message names the offending line.
  const auto row_parsed = [&] {
    ++rows;
    if (rows < 2) return;
    const auto r = static_cast<Eigen::Index>(rows - 1);
    const std::string problem =
        TimeProblem(values(0, 0), values(r - 1, 0), values(r, 0), rows, table.sample_time_s_);
    if (!problem.empty()) Fail(name, lines.number(), problem);
  };
  while (true) {
    // The common row first: `width` numbers with single commas between them and the line's end
    // right after the last (a '\r' allowed), parsed without finding the line's end first.  Any
    // other line (blank, spaces, a bad cell) goes through the checks below, from its start.
    if (rows < capacity) {
      const std::string_view rest = lines.rest();
      const char* at = rest.data();
      const char* const end = rest.data() + rest.size();
      std::size_t c = 0;
      for (; c < width; ++c) {
        double v = 0.0;
        const auto [ptr, ec] = std::from_chars(at, end, v);
        if (ec != std::errc() || ptr == at || !std::isfinite(v)) break;
        values(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(c)) = v;
        at = ptr;
        if (c + 1 < width) {
          if (at == end || *at != ',') break;
          ++at;
        }
      }
      const char* line_end = at;
      if (line_end < end && *line_end == '\r') ++line_end;
      if (c == width && (line_end == end || *line_end == '\n')) {
        lines.Consume(static_cast<std::size_t>(line_end - rest.data()));
        row_parsed();
        continue;
      }
    }
    if (!lines.Next(line)) break;
    if (TrimView(line).empty()) continue;
    if (rows == capacity) Fail(name, lines.number(), "more rows than the lines counted (a bug)");
    // The cells in place: `width` of them, each a number parsed where it lies (from_chars
    // stops at the comma); a cell that is not exactly one number, or a wrong cell count, is
    // reported with the cell's text.
    const char* at = line.data();
    const char* const end = line.data() + line.size();
    for (std::size_t c = 0; c < width; ++c) {
      const char* const cell_start = at;
      while (at < end && (*at == ' ' || *at == '\t' || *at == '\r')) ++at;
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(at, end, v);
      const char* after = ptr;
      while (after < end && (*after == ' ' || *after == '\t' || *after == '\r')) ++after;
      const bool last = c + 1 == width;
      const bool delimited = last ? after == end : (after < end && *after == ',');
      if (ec != std::errc() || ptr == at || !delimited || !std::isfinite(v)) {
        CellProblem(name, lines.number(), line, cell_start, table.columns_, c, width);
      }
      values(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(c)) = v;
      at = after + 1;
    }
    row_parsed();
  }
  if (rows < 2)
    throw CsvError(name + ": needs at least 2 data rows, found " + std::to_string(rows));
  if (rows == capacity) {
    table.data_ = std::move(values);
  } else {
    table.data_ = values.topRows(static_cast<Eigen::Index>(rows));
  }
  return table;
}

CsvTable CsvTable::FromColumns(const std::string& source, const std::vector<std::string>& names,
                               const std::vector<Eigen::VectorXd>& columns) {
  if (const std::string problem = HeaderProblem(names); !problem.empty()) {
    throw CsvError(source + ": " + problem);
  }
  if (columns.size() != names.size()) {
    throw CsvError(source + ": " + std::to_string(names.size()) + " names but " +
                   std::to_string(columns.size()) + " columns");
  }
  const Eigen::Index rows = columns.front().size();
  if (rows < 2) throw CsvError(source + ": needs at least 2 rows, found " + std::to_string(rows));
  CsvTable table;
  table.source_ = source;
  table.columns_ = names;
  table.data_.resize(rows, static_cast<Eigen::Index>(names.size()));
  for (std::size_t c = 0; c < names.size(); ++c) {
    if (columns[c].size() != rows) {
      throw CsvError(source + ": column '" + names[c] + "' has " +
                     std::to_string(columns[c].size()) + " rows, time_s has " +
                     std::to_string(rows));
    }
    for (Eigen::Index r = 0; r < rows; ++r) {
      if (!std::isfinite(columns[c](r))) {
        throw CsvError(source + ": row " + std::to_string(r + 1) + ": column '" + names[c] +
                       "' is not finite");
      }
    }
    table.data_.col(static_cast<Eigen::Index>(c)) = columns[c];
  }
  const Eigen::VectorXd& t = columns.front();
  for (Eigen::Index r = 1; r < rows; ++r) {
    const std::string problem =
        TimeProblem(t(0), t(r - 1), t(r), static_cast<std::size_t>(r + 1), table.sample_time_s_);
    if (!problem.empty()) {
      std::string message = source + ": row " + std::to_string(r + 1) + ": ";
      message += problem;
      throw CsvError(message);
    }
  }
  return table;
}

void WriteCsv(const std::string& path, const std::vector<std::string>& names,
              const std::vector<Eigen::VectorXd>& columns) {
  if (names.size() != columns.size() || columns.empty()) {
    throw CsvError(path + ": WriteCsv needs one name per column");
  }
  const Eigen::Index n = columns.front().size();
  for (const auto& c : columns) {
    if (c.size() != n) throw CsvError(path + ": WriteCsv columns differ in length");
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw CsvError(path + ": cannot open for writing");
  for (std::size_t c = 0; c < names.size(); ++c) out << (c ? "," : "") << names[c];
  out << "\n";
  char buffer[32];
  for (Eigen::Index r = 0; r < n; ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, columns[c](r));
      if (c) out << ',';
      out.write(buffer, end - buffer);
    }
    out << '\n';
  }
  if (!out.flush()) throw CsvError(path + ": write failed");
}

}  // namespace canalid::drivers
