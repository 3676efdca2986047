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

// The lines of a text, without copying: Next() gives each one (without its '\n') and counts them,
// continuing from the `first_number` lines already counted.  A text that ends with '\n' has no
// empty line after it.
class Lines {
 public:
  Lines(std::string_view text, std::size_t first_number) : rest_(text), number_(first_number) {}
  bool Next(std::string_view& line) {
    if (rest_.empty()) return false;
    ++number_;
    const void* nl = std::memchr(rest_.data(), '\n', rest_.size());
    if (nl == nullptr) {
      line = rest_;
      rest_ = {};
      return true;
    }
    const auto length = static_cast<std::size_t>(static_cast<const char*>(nl) - rest_.data());
    line = rest_.substr(0, length);
    rest_.remove_prefix(length + 1);
    return true;
  }
  std::size_t number() const { return number_; }
  /// What Next has not returned yet.
  std::string_view rest() const { return rest_; }
  /// Takes the next line as read by the caller: `length` bytes of rest() and the '\n' after
  /// them (or the end of the text).  @pre rest()[length] is '\n', or length == rest().size().
  void Consume(std::size_t length) {
    ++number_;
    rest_.remove_prefix(std::min(length + 1, rest_.size()));
  }

 private:
  std::string_view rest_;
  std::size_t number_;
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

std::size_t CsvTable::ColumnIndex(const std::string& name) const {
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (columns_[i] == name) return i;
  }
  std::string known;
  for (const auto& c : columns_) known += (known.empty() ? "" : ", ") + c;
  throw CsvError(source_ + ": no column '" + name + "' (columns: " + known + ")");
}

namespace {

// Rows of a value block for `rows` rows: a multiple of 8, so that every column starts a multiple
// of 64 bytes after the block's start, as aligned as the block itself (LargeBuffer: 64 bytes),
// at least as aligned as an Eigen::VectorXd of its own would be.  Eigen's vectorised sums peel off
// the unaligned head of a vector, so a column at another alignment sums its values in another
// order: a first version gave `canalid identify --detrend` other last bits than the column copies
// before it.
Eigen::Index AlignedRows(Eigen::Index rows) { return (rows + 7) / 8 * 8; }

// The reader behind Parse and Read: text fed in pieces of whole lines, each row's values put
// straight into their column of one column-major block, which grows by doubling unless
// reserved.  One block rather than one per column, a LargeBuffer: a block of a large file is
// backed by huge pages, whose first touch costs a page fault per 2 MiB instead of per 4 KiB
// (`canalid identify --online` over 100k rows touched 586 pages of values).
class CsvParser {
 public:
  explicit CsvParser(std::string name) : name_(std::move(name)) {}

  /// `text`: whole lines, each with its '\n'; the last piece of the input may end without one.
  void Feed(std::string_view text) {
    Lines lines(text, line_number_);
    if (!FindHeader(lines)) {
      line_number_ = lines.number();
      return;
    }
    const std::size_t width = columns_.size();
    std::string_view line;
    while (true) {
      if (rows_ == stride_) Grow();
      double* const row = values_.data() + rows_;
      // The common row first: `width` numbers with single commas between them and the line's
      // end right after the last (a '\r' allowed), parsed without finding the line's end first.
      // Any other line (blank, spaces, a bad cell) goes through the checks below, from its start.
      const std::string_view rest = lines.rest();
      const char* at = rest.data();
      const char* const end = rest.data() + rest.size();
      std::size_t c = 0;
      for (; c < width; ++c) {
        double v = 0.0;
        const auto [ptr, ec] = std::from_chars(at, end, v);
        if (ec != std::errc() || ptr == at || !std::isfinite(v)) break;
        row[static_cast<Eigen::Index>(c) * stride_] = v;
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
        RowParsed(lines.number());
        continue;
      }
      if (!lines.Next(line)) break;
      if (TrimView(line).empty()) continue;
      // The cells in place: `width` of them, each a number parsed where it lies (from_chars
      // stops at the comma); a cell that is not exactly one number, or a wrong cell count, is
      // reported with the cell's text.
      at = line.data();
      const char* const line_stop = line.data() + line.size();
      for (c = 0; c < width; ++c) {
        const char* const cell_start = at;
        while (at < line_stop && (*at == ' ' || *at == '\t' || *at == '\r')) ++at;
        double v = 0.0;
        const auto [ptr, ec] = std::from_chars(at, line_stop, v);
        const char* after = ptr;
        while (after < line_stop && (*after == ' ' || *after == '\t' || *after == '\r')) ++after;
        const bool last = c + 1 == width;
        const bool delimited = last ? after == line_stop : (after < line_stop && *after == ',');
        if (ec != std::errc() || ptr == at || !delimited || !std::isfinite(v)) {
          CellProblem(name_, lines.number(), line, cell_start, columns_, c, width);
        }
        row[static_cast<Eigen::Index>(c) * stride_] = v;
        at = after + 1;
      }
      RowParsed(lines.number());
    }
    line_number_ = lines.number();
  }

  /// Room for `rows` rows in every column, once the header has been read (nothing when there is
  /// room already).
  void Reserve(Eigen::Index rows) {
    if (!header_ || rows <= stride_) return;
    const Eigen::Index stride = AlignedRows(rows);
    const auto width = static_cast<Eigen::Index>(columns_.size());
    core::LargeBuffer bigger(static_cast<std::size_t>(stride * width));
    for (Eigen::Index c = 0; c < width; ++c) {
      std::copy_n(values_.data() + c * stride_, rows_, bigger.data() + c * stride);
    }
    values_ = std::move(bigger);
    stride_ = stride;
  }
  Eigen::Index rows() const { return rows_; }

  struct Parsed {
    std::vector<std::string> columns;
    core::LargeBuffer values;  // column c from values.data() + c * stride
    Eigen::Index stride;
    Eigen::Index rows;
    double sample_time_s;
  };
  /// What was parsed: the first rows of each column.  @throws CsvError without a header or 2
  /// rows.
  Parsed Finish() && {
    if (!header_) throw CsvError(name_ + ": empty file (no header row)");
    if (rows_ < 2) {
      throw CsvError(name_ + ": needs at least 2 data rows, found " + std::to_string(rows_));
    }
    return {std::move(columns_), std::move(values_), stride_, rows_, sample_time_s_};
  }

 private:
  // Header: the first line that is not blank.  False while there is none yet.
  bool FindHeader(Lines& lines) {
    std::string_view line;
    while (!header_ && lines.Next(line)) {
      if (TrimView(line).empty()) continue;
      columns_ = SplitCells(line);
      if (const std::string problem = HeaderProblem(columns_); !problem.empty()) {
        Fail(name_, lines.number(), problem);
      }
      header_ = true;
    }
    return header_;
  }

  void Grow() { Reserve(std::max<Eigen::Index>(1024, 2 * stride_)); }

  // Time checks as rows arrive, so the message names the offending line.
  void RowParsed(std::size_t line_number) {
    ++rows_;
    if (rows_ < 2) return;
    const double* const t = values_.data();  // column 0
    const Eigen::Index r = rows_ - 1;
    const std::string problem =
        TimeProblem(t[0], t[r - 1], t[r], static_cast<std::size_t>(rows_), sample_time_s_);
    if (!problem.empty()) Fail(name_, line_number, problem);
  }

  std::string name_;
  std::size_t line_number_ = 0;  // lines fed so far
  bool header_ = false;
  std::vector<std::string> columns_;
  core::LargeBuffer values_;  // column c from values_.data() + c * stride_, rows_ rows used
  Eigen::Index stride_ = 0;
  Eigen::Index rows_ = 0;
  double sample_time_s_ = 0.0;
};

}  // namespace

CsvTable::CsvTable(std::string source, std::vector<std::string> columns, core::LargeBuffer values,
                   Eigen::Index stride, Eigen::Index rows, double sample_time_s)
    : source_(std::move(source)),
      columns_(std::move(columns)),
      values_(std::move(values)),
      stride_(stride),
      rows_(rows),
      sample_time_s_(sample_time_s) {}

CsvTable CsvTable::Read(const std::string& path) { return Read(path, kReadChunkBytes); }

CsvTable CsvTable::Read(const std::string& path, std::size_t chunk_bytes) {
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
  // A chunk at a time, from the descriptor already open (a pipe cannot be opened twice), into one
  // buffer reused for the whole file: the parser gets the whole lines read so far and the
  // unfinished last one moves to the buffer's start.  The buffer grows only for a line longer
  // than it.  (A buffer of the whole file would be written once and read once, and its pages
  // cost more than the parsing; mapping the file instead dies of SIGBUS when another process
  // shrinks it.)
  std::size_t capacity = std::max<std::size_t>(chunk_bytes, 1);
  auto buffer = std::make_unique_for_overwrite<char[]>(capacity);
  std::size_t size = 0;
  CsvParser parser(path);
  std::size_t fed = 0;
  bool reserved = false;
  while (true) {
    if (size == capacity) {
      auto bigger = std::make_unique_for_overwrite<char[]>(2 * capacity);
      std::memcpy(bigger.get(), buffer.get(), size);
      buffer = std::move(bigger);
      capacity *= 2;
    }
    const ssize_t n = ::read(file.fd, buffer.get() + size, capacity - size);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw CsvError(path + ": cannot read file (" + core::ErrnoText(errno) + ")");
    }
    if (n == 0) break;
    const std::string_view read(buffer.get() + size, static_cast<std::size_t>(n));
    const std::size_t last_newline = read.rfind('\n');
    size += static_cast<std::size_t>(n);
    if (last_newline == std::string_view::npos) continue;
    const std::size_t whole =
        static_cast<std::size_t>(read.data() - buffer.get()) + last_newline + 1;
    parser.Feed(std::string_view(buffer.get(), whole));
    fed += whole;
    if (!reserved && parser.rows() > 0 && S_ISREG(st.st_mode)) {
      // The first rows tell the bytes per row: room for the whole file at once (a quarter more,
      // for rows that get longer), one allocation instead of one per doubling.
      const double rows_per_byte = static_cast<double>(parser.rows()) / static_cast<double>(fed);
      parser.Reserve(
          static_cast<Eigen::Index>(1.25 * rows_per_byte * static_cast<double>(st.st_size)) + 16);
      reserved = true;
    }
    std::memmove(buffer.get(), buffer.get() + whole, size - whole);
    size -= whole;
  }
  parser.Feed(std::string_view(buffer.get(), size));
  CsvParser::Parsed p = std::move(parser).Finish();
  return CsvTable(path, std::move(p.columns), std::move(p.values), p.stride, p.rows,
                  p.sample_time_s);
}

CsvTable CsvTable::Parse(std::string_view text, const std::string& name) {
  CsvParser parser(name);
  parser.Feed(text);
  CsvParser::Parsed p = std::move(parser).Finish();
  return CsvTable(name, std::move(p.columns), std::move(p.values), p.stride, p.rows,
                  p.sample_time_s);
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
  }
  const Eigen::VectorXd& t = columns.front();
  double sample_time_s = 0.0;
  for (Eigen::Index r = 1; r < rows; ++r) {
    const std::string problem =
        TimeProblem(t(0), t(r - 1), t(r), static_cast<std::size_t>(r + 1), sample_time_s);
    if (!problem.empty()) {
      std::string message = source + ": row " + std::to_string(r + 1) + ": ";
      message += problem;
      throw CsvError(message);
    }
  }
  const Eigen::Index stride = AlignedRows(rows);
  core::LargeBuffer values(names.size() * static_cast<std::size_t>(stride));
  for (std::size_t c = 0; c < names.size(); ++c) {
    std::copy_n(columns[c].data(), rows, values.data() + static_cast<Eigen::Index>(c) * stride);
  }
  return CsvTable(source, names, std::move(values), stride, rows, sample_time_s);
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
