#include "drivers/csv/csv_table.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace canalid::drivers {
namespace {

std::string ErrorOf(const std::string& text) {
  try {
    CsvTable::Parse(text, "f.csv");
  } catch (const CsvError& e) {
    return e.what();
  }
  return "no error";
}

TEST(CsvTable, ReadsColumnsAndSampleTime) {
  const CsvTable t = CsvTable::Parse("time_s,a,b\n0,1,2\n0.5,3,4\n1.0,5,6\n", "f.csv");
  EXPECT_EQ(t.rows(), 3);
  EXPECT_DOUBLE_EQ(t.sample_time_s(), 0.5);
  EXPECT_DOUBLE_EQ(t.Column("b")(2), 6.0);
  EXPECT_TRUE(t.HasColumn("a"));
}

TEST(CsvTable, NamesFileLineAndColumnInEveryError) {
  EXPECT_EQ(ErrorOf(""), "f.csv: empty file (no header row)");
  EXPECT_EQ(ErrorOf("t,a\n0,1\n1,2\n"), "f.csv:1: the first column must be 'time_s' (found 't')");
  EXPECT_EQ(ErrorOf("time_s,a,a\n0,1,1\n"), "f.csv:1: column 'a' appears twice");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n1,abc\n"), "f.csv:3: column 'a': 'abc' is not a number");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n1,nan\n"), "f.csv:3: column 'a': 'nan' is not finite");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n1\n"), "f.csv:3: expected 2 cells, found 1");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n1,2\n0.5,3\n"),
            "f.csv:4: time_s 0.5 does not increase (previous 1)");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n1,2\n2,3\n4,3\n"),
            "f.csv:5: time_s 4 breaks uniform sampling (expected 3, sample time 1 s)");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n"), "f.csv: needs at least 2 data rows, found 1");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n1,"), "f.csv:3: column 'a': '' is not a number");
}

TEST(CsvTable, ToleratesCarriageReturnsAndFloatingPointTime) {
  std::string text = "time_s,a\r\n";
  for (int k = 0; k < 1000; ++k) text += std::to_string(0.1 * k) + ",1\r\n";
  const CsvTable t = CsvTable::Parse(text, "f.csv");
  EXPECT_EQ(t.rows(), 1000);
  EXPECT_NEAR(t.sample_time_s(), 0.1, 1e-9);
}

TEST(CsvTable, MissingColumnListsTheOnesThereAre) {
  const CsvTable t = CsvTable::Parse("time_s,a,b\n0,1,2\n1,3,4\n", "f.csv");
  try {
    t.Column("level");
    FAIL() << "no error";
  } catch (const CsvError& e) {
    EXPECT_STREQ(e.what(), "f.csv: no column 'level' (columns: time_s, a, b)");
  }
}

std::string FromColumnsErrorOf(const std::vector<std::string>& names,
                               const std::vector<Eigen::VectorXd>& columns) {
  try {
    CsvTable::FromColumns("log.lcm reach 2", names, columns);
  } catch (const CsvError& e) {
    return e.what();
  }
  return "no error";
}

TEST(CsvTable, FromColumnsHoldsTheColumnsAsAParsedFileWould) {
  const Eigen::VectorXd t = Eigen::Vector3d(10.0, 10.5, 11.0);
  const Eigen::VectorXd a = Eigen::Vector3d(1.0, 2.0, 3.0);
  const CsvTable table = CsvTable::FromColumns("log.lcm reach 2", {"time_s", "a"}, {t, a});
  const CsvTable parsed = CsvTable::Parse("time_s,a\n10,1\n10.5,2\n11,3\n", "f.csv");
  EXPECT_EQ(table.source(), "log.lcm reach 2");
  EXPECT_EQ(table.columns(), parsed.columns());
  EXPECT_EQ(table.rows(), parsed.rows());
  EXPECT_EQ(table.sample_time_s(), parsed.sample_time_s());
  EXPECT_EQ(table.Column("a"), parsed.Column("a"));
  EXPECT_EQ(table.time_s(), parsed.time_s());
}

TEST(CsvTable, FromColumnsRejectsWhatReadRejects) {
  const Eigen::VectorXd t = Eigen::Vector3d(0.0, 1.0, 2.0);
  const Eigen::VectorXd a = Eigen::Vector3d(1.0, 2.0, 3.0);
  EXPECT_EQ(FromColumnsErrorOf({"t", "a"}, {t, a}),
            "log.lcm reach 2: the first column must be 'time_s' (found 't')");
  EXPECT_EQ(FromColumnsErrorOf({"time_s", "a", "a"}, {t, a, a}),
            "log.lcm reach 2: column 'a' appears twice");
  EXPECT_EQ(FromColumnsErrorOf({"time_s", "a"}, {t}), "log.lcm reach 2: 2 names but 1 columns");
  EXPECT_EQ(FromColumnsErrorOf({"time_s", "a"}, {t, Eigen::Vector2d(1.0, 2.0)}),
            "log.lcm reach 2: column 'a' has 2 rows, time_s has 3");
  EXPECT_EQ(FromColumnsErrorOf({"time_s", "a"}, {t, Eigen::Vector3d(1.0, NAN, 3.0)}),
            "log.lcm reach 2: row 2: column 'a' is not finite");
  EXPECT_EQ(FromColumnsErrorOf({"time_s", "a"}, {Eigen::Vector3d(0.0, 1.0, 0.5), a}),
            "log.lcm reach 2: row 3: time_s 0.5 does not increase (previous 1)");
  EXPECT_EQ(
      FromColumnsErrorOf({"time_s", "a"}, {Eigen::Vector3d(0.0, 1.0, 3.0), a}),
      "log.lcm reach 2: row 3: time_s 3 breaks uniform sampling (expected 2, sample time 1 s)");
  EXPECT_EQ(FromColumnsErrorOf({"time_s"}, {Eigen::VectorXd::Zero(1)}),
            "log.lcm reach 2: needs at least 2 rows, found 1");
}

TEST(CsvTable, MissingFileIsAnError) {
  EXPECT_THROW(CsvTable::Read("/nonexistent/x.csv"), CsvError);
}

// The parser reads cells in place: spaces and tabs around a number, blank lines and a last line
// without its newline are as before; a cell with anything after its number is not a number.
TEST(CsvTable, CellsAreReadInPlaceWithTheirSpaces) {
  const CsvTable t = CsvTable::Parse("\n time_s , a\n\n0 ,\t1.5\n 1, -2e-3 \n\n2,3", "f.csv");
  EXPECT_EQ(t.rows(), 3);
  EXPECT_EQ(t.columns(), (std::vector<std::string>{"time_s", "a"}));
  EXPECT_EQ(t.Column("a")(1), -2e-3);
  EXPECT_EQ(t.Column("a")(2), 3.0);
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n1,2 3\n"), "f.csv:3: column 'a': '2 3' is not a number");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n1,+2\n"), "f.csv:3: column 'a': '+2' is not a number");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n1,2,3\n"), "f.csv:3: expected 2 cells, found 3");
  EXPECT_EQ(ErrorOf("time_s,a\n0,1\n,2\n"), "f.csv:3: column 'time_s': '' is not a number");
}

// A reference reader for the test, one line and one cell at a time (split at commas, spaces
// trimmed, std::stod), against which the parser's in-place rows are checked.
std::vector<std::vector<double>> ReferenceRows(const std::string& text) {
  std::vector<std::vector<double>> rows;
  std::istringstream in(text);
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (header) {
      header = false;
      continue;
    }
    std::vector<double> row;
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

// A record of `rows` rows in one of the line shapes the parser meets: "plain", "crlf", "blank
// lines", "spaces" (around some cells) or "no last newline".
std::string ShapedText(const std::string& kind, int rows) {
  std::string text = "time_s,a,b\n";
  for (int k = 0; k < rows; ++k) {
    const std::string t = std::to_string(0.25 * k);
    const std::string a = std::to_string(std::sin(0.01 * k));
    const std::string b = std::to_string(k % 7 - 3) + "e-" + std::to_string(k % 5);
    if (kind == "spaces" && k % 3 == 0) {
      text.append(" ").append(t).append(" ,\t").append(a).append(", ").append(b).append(" \n");
    } else {
      text.append(t).append(",").append(a).append(",").append(b);
      text.append(kind == "crlf" ? "\r\n" : "\n");
    }
    if (kind == "blank lines" && k % 1000 == 999) text += "\n  \n";
  }
  if (kind == "no last newline") text.pop_back();
  return text;
}

constexpr const char* kShapes[] = {"plain", "crlf", "blank lines", "spaces", "no last newline"};

// Rows in the common shape are parsed without looking for the line's end first: long files
// (their columns grow several times), with and without blank lines, CRLF, spaces and a last
// line without its newline, all give what a line-by-line reader gives, and an error after
// thousands of rows still names its line.
TEST(CsvTable, LongFilesOfEveryLineShapeMatchALineByLineReader) {
  for (const std::string kind : kShapes) {
    const std::string text = ShapedText(kind, 40000);
    const CsvTable t = CsvTable::Parse(text, "f.csv");
    const std::vector<std::vector<double>> expected = ReferenceRows(text);
    ASSERT_EQ(t.rows(), static_cast<Eigen::Index>(expected.size())) << kind;
    const auto a = t.Column("a");
    const auto b = t.Column("b");
    for (std::size_t r = 0; r < expected.size(); ++r) {
      const auto i = static_cast<Eigen::Index>(r);
      ASSERT_EQ(t.time_s()(i), expected[r][0]) << kind << " row " << r;
      ASSERT_EQ(a(i), expected[r][1]) << kind << " row " << r;
      ASSERT_EQ(b(i), expected[r][2]) << kind << " row " << r;
    }
    EXPECT_DOUBLE_EQ(t.sample_time_s(), 0.25) << kind;
  }
  std::string text = "time_s,a\n";
  for (int k = 0; k < 4000; ++k) text += std::to_string(k) + "," + std::to_string(k) + "\n";
  EXPECT_EQ(ErrorOf(text + "4000,x\n"), "f.csv:4002: column 'a': 'x' is not a number");
  EXPECT_EQ(ErrorOf(text + "4001,1\n"),
            "f.csv:4002: time_s 4001 breaks uniform sampling (expected 4000, sample time 1 s)");
  EXPECT_EQ(ErrorOf(text + "4000,1,2\n"), "f.csv:4002: expected 2 cells, found 3");
  EXPECT_EQ(ErrorOf(text + "4000,1\r\r5\n"), "f.csv:4002: column 'a': '1\r\r5' is not a number");
}

// A scratch directory for one test, removed with it.
class TempDir {
 public:
  TempDir()
      : path_(std::filesystem::temp_directory_path() /
              ("csv_table_test_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string File(const std::string& name, const std::string& text) const {
    const std::filesystem::path file = path_ / name;
    std::ofstream(file, std::ios::binary) << text;
    return file.string();
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Every column starts as aligned as an Eigen::VectorXd of its own (16 bytes at the x86-64
// baseline), whatever the row count, from Parse, Read and FromColumns alike: Eigen's vectorised
// sums over a column, e.g. the detrending of `canalid identify --detrend`, then add its values
// in the same order as over a copy, to the last bit.
TEST(CsvTable, EveryColumnIsAlignedAsAVectorOfItsOwn) {
  const auto aligned = [](const CsvTable& t) {
    for (const std::string& name : t.columns()) {
      if (reinterpret_cast<std::uintptr_t>(t.Column(name).data()) % 16 != 0) return false;
    }
    return true;
  };
  const TempDir dir;
  for (int rows = 2; rows <= 19; ++rows) {
    std::string text = "time_s,a,b,c\n";
    for (int k = 0; k < rows; ++k) text += std::to_string(k) + ",1,2,3\n";
    EXPECT_TRUE(aligned(CsvTable::Parse(text, "f.csv"))) << rows << " rows";
    EXPECT_TRUE(aligned(CsvTable::Read(dir.File("f.csv", text)))) << rows << " rows";
    const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(rows, 0.0, rows - 1.0);
    EXPECT_TRUE(aligned(CsvTable::FromColumns("log", {"time_s", "a", "b"}, {t, t, t})))
        << rows << " rows";
  }
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(1001, 0.0, 1.0).array().sin();
  std::string text = "time_s,a,b\n";
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    text += std::to_string(k) + "," + std::to_string(x(k)) + "," + std::to_string(-x(k)) + "\n";
  }
  const CsvTable table = CsvTable::Read(dir.File("x.csv", text));
  const Eigen::VectorXd copy = table.Column("b");
  EXPECT_EQ(table.Column("b").sum(), copy.sum());
  EXPECT_EQ(table.Column("b").squaredNorm(), copy.squaredNorm());
}

std::string ReadErrorOf(const std::string& path, std::size_t chunk_bytes) {
  try {
    CsvTable::Read(path, chunk_bytes);
  } catch (const CsvError& e) {
    return e.what();
  }
  return "no error";
}

// Read parses a file a chunk at a time: lines cut anywhere by the chunks (1 byte, a few bytes,
// the default), and lines longer than a chunk, give the table Parse gives from the whole text,
// and errors name the same line.
TEST(CsvTable, ReadingInChunksGivesWhatParsingTheWholeTextGives) {
  const TempDir dir;
  for (const std::string kind : kShapes) {
    const std::string text = ShapedText(kind, 3000);
    const std::string path = dir.File("f.csv", text);
    const CsvTable whole = CsvTable::Parse(text, path);
    for (const std::size_t chunk : {std::size_t{1}, std::size_t{3}, std::size_t{7}, std::size_t{64},
                                    std::size_t{4093}, CsvTable::kReadChunkBytes}) {
      const CsvTable read = CsvTable::Read(path, chunk);
      ASSERT_EQ(read.rows(), whole.rows()) << kind << ", chunk " << chunk;
      EXPECT_EQ(read.columns(), whole.columns()) << kind << ", chunk " << chunk;
      EXPECT_EQ(read.time_s(), whole.time_s()) << kind << ", chunk " << chunk;
      EXPECT_EQ(read.Column("a"), whole.Column("a")) << kind << ", chunk " << chunk;
      EXPECT_EQ(read.Column("b"), whole.Column("b")) << kind << ", chunk " << chunk;
      EXPECT_EQ(read.sample_time_s(), whole.sample_time_s()) << kind << ", chunk " << chunk;
    }
  }
  std::string text = "\n\ntime_s,a\n";
  for (int k = 0; k < 4000; ++k) text += std::to_string(k) + "," + std::to_string(k) + "\n";
  const std::string bad = dir.File("bad.csv", text + "4000,x\n");
  const std::string late = dir.File("late.csv", text + "4001,1\n");
  const std::string header_only = dir.File("header.csv", "\n  \ntime_s,a\n\n");
  for (const std::size_t chunk : {std::size_t{1}, std::size_t{5}, CsvTable::kReadChunkBytes}) {
    EXPECT_EQ(ReadErrorOf(bad, chunk), bad + ":4004: column 'a': 'x' is not a number");
    EXPECT_EQ(ReadErrorOf(late, chunk),
              late + ":4004: time_s 4001 breaks uniform sampling (expected 4000, sample time 1 s)");
    EXPECT_EQ(ReadErrorOf(header_only, chunk),
              header_only + ": needs at least 2 data rows, found 0");
  }
}

// Read reads a regular file and anything else (a pipe, /dev/stdin) alike, with the same
// result; a directory is named as such.
TEST(CsvTable, ReadsFilesAndStreamsAlikeAndRefusesADirectory) {
  const TempDir temp;
  const std::filesystem::path& dir = temp.path();
  const std::string text = "time_s,a\n0,1\n1,2\n2,4\n";
  const CsvTable file = CsvTable::Read(temp.File("f.csv", text));
  EXPECT_EQ(file.Column("a")(2), 4.0);
  EXPECT_EQ(file.source(), (dir / "f.csv").string());
  ASSERT_EQ(::mkfifo((dir / "pipe").c_str(), 0600), 0);
  std::thread writer([&] { std::ofstream(dir / "pipe") << text; });
  Eigen::VectorXd piped;
  try {
    piped = CsvTable::Read((dir / "pipe").string()).Column("a");
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what();
    // The writer waits for a reader: give it one, so that it ends.
    const int fd = ::open((dir / "pipe").c_str(), O_RDONLY | O_NONBLOCK);
    writer.join();
    ::close(fd);
    return;
  }
  writer.join();
  EXPECT_EQ(piped, file.Column("a"));
  try {
    CsvTable::Read(dir.string());
    ADD_FAILURE() << "a directory was read";
  } catch (const CsvError& e) {
    EXPECT_EQ(std::string(e.what()), dir.string() + ": is a directory, not a CSV file");
  }
}

}  // namespace
}  // namespace canalid::drivers
