#pragma once
#include <toml++/toml.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/toml/toml_reader.h"

namespace canalid::sim {

/// Every problem found in a configuration file, one "file:line:column: message" per entry.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(std::vector<std::string> problems);
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  std::vector<std::string> problems_;
};

/// The simulator's files' vocabulary over core::TomlReader: reads typed values out of a parsed
/// TOML document and collects the problems ("file:line:column: message", the message naming the
/// key path) instead of stopping at the first one.  Call Finish() at the end.
class ConfigReader final {
 public:
  /// Parses the file.  @throws ConfigError with the parser's location on a syntax error.
  explicit ConfigReader(const std::string& path);
  /// Parses `text` as if it were the contents of the file `name` (messages name `name`).
  /// @throws ConfigError with the parser's location on a syntax error.
  static ConfigReader FromText(std::string_view text, const std::string& name);
  const toml::table& root() const { return toml_.root(); }
  const std::string& path() const { return toml_.name(); }

  /// A number in [lo, hi]; a missing key yields `fallback` or, without one, a problem.
  double Number(const toml::table& table, std::string_view key, std::string_view where,
                std::optional<double> fallback, double lo, double hi);
  /// An integer in [lo, hi] (a float such as 7.0 is not accepted).
  std::int64_t Integer(const toml::table& table, std::string_view key, std::string_view where,
                       std::optional<std::int64_t> fallback, std::int64_t lo, std::int64_t hi);
  std::string String(const toml::table& table, std::string_view key, std::string_view where,
                     const std::optional<std::string>& fallback);
  /// One of `allowed`; reports the allowed values otherwise.
  std::string Choice(const toml::table& table, std::string_view key, std::string_view where,
                     const std::optional<std::string>& fallback,
                     std::initializer_list<std::string_view> allowed);
  /// Unknown keys are errors (a typo must not be ignored silently).
  void CheckKeys(const toml::table& table, std::string_view where,
                 std::initializer_list<std::string_view> allowed);
  void Problem(const toml::source_region& region, const std::string& message);
  /// Element `index` of an array of tables ([[name]]), or null after the problem
  /// "<where> must be a table".
  const toml::table* TableAt(const toml::array& array, std::size_t index, const std::string& where);
  bool HasProblems() const { return toml_.HasProblems(); }
  /// @throws ConfigError if any problem was recorded.
  void Finish() const;
  /// Finish(), then `validate()`, whose std::invalid_argument becomes the ConfigError
  /// "<path>: <what>" (a file that reads cleanly but describes an impossible canal).
  template <class Validate>
  void FinishValidated(Validate&& validate) const {
    Finish();
    try {
      validate();
    } catch (const std::invalid_argument& e) {
      throw ConfigError({path() + ": " + e.what()});
    }
  }

 private:
  explicit ConfigReader(core::TomlReader toml) : toml_(std::move(toml)) {}

  core::TomlReader toml_;
};

/// "where.key" or "key" when where is empty.
std::string KeyPath(std::string_view where, std::string_view key);

}  // namespace canalid::sim
