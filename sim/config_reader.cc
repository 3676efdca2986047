#include "sim/config_reader.h"

#include <algorithm>
#include <sstream>
#include <utility>

namespace canalid::sim {
namespace {

std::string Join(const std::vector<std::string>& problems) {
  std::string all;
  for (const std::string& p : problems) all += (all.empty() ? "" : "\n") + p;
  return all;
}

}  // namespace

ConfigError::ConfigError(std::vector<std::string> problems)
    : std::runtime_error(Join(problems)), problems_(std::move(problems)) {}

std::string KeyPath(std::string_view where, std::string_view key) {
  return core::TomlKeyPath(where, key);
}

namespace {

ConfigError FromTomlError(const core::TomlError& e) {
  std::vector<std::string> problems;
  for (const core::TomlIssue& issue : e.issues()) problems.push_back(issue.ToString());
  return ConfigError(std::move(problems));
}

core::TomlReader ReadFile(const std::string& path) {
  try {
    return core::TomlReader::FromFile(path);
  } catch (const core::TomlError& e) {
    throw FromTomlError(e);
  }
}

core::TomlReader ReadText(std::string_view text, const std::string& name) {
  try {
    return core::TomlReader(text, name);
  } catch (const core::TomlError& e) {
    throw FromTomlError(e);
  }
}

}  // namespace

ConfigReader::ConfigReader(const std::string& path) : toml_(ReadFile(path)) {}

ConfigReader ConfigReader::FromText(std::string_view text, const std::string& name) {
  return ConfigReader(ReadText(text, name));
}

void ConfigReader::Problem(const toml::source_region& region, const std::string& message) {
  // The message names its key path itself (the simulator's wording).
  toml_.Problem(region, "", message);
}

double ConfigReader::Number(const toml::table& table, std::string_view key, std::string_view where,
                            std::optional<double> fallback, double lo, double hi) {
  const toml::node* node = table.get(key);
  if (node == nullptr) {
    if (!fallback) Problem(table.source(), "missing key '" + KeyPath(where, key) + "'");
    return fallback.value_or(0.0);
  }
  std::optional<double> value = node->value<double>();
  if (!value || !(node->is_floating_point() || node->is_integer())) {
    Problem(node->source(), "'" + KeyPath(where, key) + "' must be a number");
    return fallback.value_or(0.0);
  }
  if (!(*value >= lo && *value <= hi)) {
    std::ostringstream os;
    os << "'" << KeyPath(where, key) << "' = " << *value << " is outside [" << lo << ", " << hi
       << "]";
    Problem(node->source(), os.str());
  }
  return *value;
}

std::int64_t ConfigReader::Integer(const toml::table& table, std::string_view key,
                                   std::string_view where, std::optional<std::int64_t> fallback,
                                   std::int64_t lo, std::int64_t hi) {
  const toml::node* node = table.get(key);
  if (node == nullptr) {
    if (!fallback) Problem(table.source(), "missing key '" + KeyPath(where, key) + "'");
    return fallback.value_or(0);
  }
  if (!node->is_integer()) {
    Problem(node->source(), "'" + KeyPath(where, key) + "' must be an integer");
    return fallback.value_or(0);
  }
  const std::int64_t value = *node->value<std::int64_t>();
  if (value < lo || value > hi) {
    std::ostringstream os;
    os << "'" << KeyPath(where, key) << "' = " << value << " is outside [" << lo << ", " << hi
       << "]";
    Problem(node->source(), os.str());
  }
  return value;
}

std::string ConfigReader::String(const toml::table& table, std::string_view key,
                                 std::string_view where,
                                 const std::optional<std::string>& fallback) {
  const toml::node* node = table.get(key);
  if (node == nullptr) {
    if (!fallback) Problem(table.source(), "missing key '" + KeyPath(where, key) + "'");
    return fallback.value_or("");
  }
  if (!node->is_string()) {
    Problem(node->source(), "'" + KeyPath(where, key) + "' must be a string");
    return fallback.value_or("");
  }
  return std::string(*node->value<std::string_view>());
}

std::string ConfigReader::Choice(const toml::table& table, std::string_view key,
                                 std::string_view where, const std::optional<std::string>& fallback,
                                 std::initializer_list<std::string_view> allowed) {
  std::string value = String(table, key, where, fallback);
  if (std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
    const toml::node* node = table.get(key);
    Problem(node != nullptr ? node->source() : table.source(),
            "'" + KeyPath(where, key) + "' = \"" + value + "\" must be one of " +
                core::JoinNames(allowed, "\""));
  }
  return value;
}

void ConfigReader::CheckKeys(const toml::table& table, std::string_view where,
                             std::initializer_list<std::string_view> allowed) {
  for (const auto& [key, region] : core::TomlReader::UnknownKeys(table, allowed)) {
    Problem(region, "unknown key '" + KeyPath(where, key) +
                        "' (allowed: " + core::JoinNames(allowed) + ")");
  }
}

const toml::table* ConfigReader::TableAt(const toml::array& array, std::size_t index,
                                         const std::string& where) {
  const toml::table* t = array[index].as_table();
  if (t == nullptr) Problem(array[index].source(), where + " must be a table");
  return t;
}

void ConfigReader::Finish() const {
  if (!toml_.HasProblems()) return;
  std::vector<std::string> messages;
  for (const core::TomlIssue& issue : toml_.Issues()) messages.push_back(issue.ToString());
  throw ConfigError(messages);
}

}  // namespace canalid::sim
