#pragma once
#include <toml++/toml.h>

#include <initializer_list>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace canalid::core {

/// One problem of a TOML file, printed by ToString() as
///   file:line:column: message          (path empty: the message names its keys itself)
///   file:line:column: path: message
/// with line and column 1-based: the key's or its value's position, or its table's when the key
/// is missing.
struct TomlIssue {
  std::string file;
  int line = 1;
  int column = 1;
  std::string path;  ///< TOML key path, 0-based array indices: "channel[2].plc"; may be ""
  std::string message;
  std::string ToString() const;
};

/// Every problem of a TOML file at once, in file order.  what() is all of them, one per line.
class TomlError : public std::runtime_error {
 public:
  explicit TomlError(std::vector<TomlIssue> issues);
  const std::vector<TomlIssue>& issues() const { return issues_; }

 private:
  std::vector<TomlIssue> issues_;
};

/// A parsed TOML document (toml++) and the problems its reader finds in it, each with its
/// position.  The schema (which keys, which types, which messages) is the caller's: this holds
/// the document, the file name and the positions.  Text parsing only; FromFile reads the file.
class TomlReader final {
 public:
  /// Parses `text`; `name` is the file named in every message.
  /// @throws TomlError with one issue (the parser's position and description) on a syntax error.
  TomlReader(std::string_view text, std::string name);
  /// Reads the file `path` and parses it.  @throws TomlError: "path:1:1: cannot read the file",
  /// or the syntax error.
  static TomlReader FromFile(const std::string& path);

  const toml::table& root() const { return root_; }
  const std::string& name() const { return name_; }

  /// Records a problem at the start of `where` (a region without a position counts as 1:1).
  void Problem(const toml::source_region& where, std::string path, std::string message);
  bool HasProblems() const { return !issues_.empty(); }
  /// The problems so far in file order (line, then column; at one position in the order found).
  std::vector<TomlIssue> Issues() const;

  /// Remembers where the key path `path` is, for Locate.
  void Mark(const std::string& path, const toml::source_region& where);
  /// The region marked for `path` or else for its nearest enclosing path ("reach[0].level" ->
  /// "reach[0]" -> "reach"); an empty region (1:1) when none is marked.
  toml::source_region Locate(std::string path) const;

  /// The keys of `table` that are not in `allowed`, with their positions, in the table's order.
  static std::vector<std::pair<std::string, toml::source_region>> UnknownKeys(
      const toml::table& table, std::initializer_list<std::string_view> allowed);

 private:
  std::string name_;
  toml::table root_;
  std::vector<TomlIssue> issues_;
  std::map<std::string, toml::source_region, std::less<>> positions_;
};

/// "where.key", or "key" when `where` is empty.
std::string TomlKeyPath(std::string_view where, std::string_view key);

/// "a string", "an integer", "a float", "a boolean", "a table", "an array", "a date or time".
const char* TomlTypeName(const toml::node& node);

/// The names joined by ", ", each between `quote` characters ("a, b" or "\"a\", \"b\"").
std::string JoinNames(std::initializer_list<std::string_view> names, std::string_view quote = "");

}  // namespace canalid::core
