#include "sim/config_reader.h"

#include <algorithm>
#include <sstream>

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
  return where.empty() ? std::string(key) : std::string(where) + "." + std::string(key);
}

ConfigReader::ConfigReader(const std::string& path) : path_(path) {
  try {
    root_ = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw SyntaxError(e);
  }
}

ConfigReader ConfigReader::FromText(std::string_view text, const std::string& name) {
  ConfigReader reader;
  reader.path_ = name;
  try {
    reader.root_ = toml::parse(text, name);
  } catch (const toml::parse_error& e) {
    throw reader.SyntaxError(e);
  }
  return reader;
}

ConfigError ConfigReader::SyntaxError(const toml::parse_error& e) const {
  std::ostringstream os;
  os << path_ << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
     << e.description();
  return ConfigError({os.str()});
}

void ConfigReader::Problem(const toml::source_region& region, const std::string& message) {
  std::ostringstream os;
  os << path_ << ":" << region.begin.line << ":" << region.begin.column << ": " << message;
  // Keep the file's order: problems are found table by table, not line by line.
  auto at = problems_.begin();
  while (at != problems_.end() &&
         (at->first.line < region.begin.line ||
          (at->first.line == region.begin.line && at->first.column <= region.begin.column))) {
    ++at;
  }
  problems_.insert(at, {region.begin, os.str()});
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
                                 std::string_view where, std::optional<std::string> fallback) {
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
                                 std::string_view where, std::optional<std::string> fallback,
                                 std::initializer_list<std::string_view> allowed) {
  std::string value = String(table, key, where, fallback);
  if (std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
    std::string list;
    for (std::string_view a : allowed)
      list += (list.empty() ? "\"" : ", \"") + std::string(a) + "\"";
    const toml::node* node = table.get(key);
    Problem(node != nullptr ? node->source() : table.source(),
            "'" + KeyPath(where, key) + "' = \"" + value + "\" must be one of " + list);
  }
  return value;
}

void ConfigReader::CheckKeys(const toml::table& table, std::string_view where,
                             std::initializer_list<std::string_view> allowed) {
  for (const auto& [key, node] : table) {
    if (std::find(allowed.begin(), allowed.end(), key.str()) == allowed.end()) {
      std::string list;
      for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      Problem(key.source(),
              "unknown key '" + KeyPath(where, key.str()) + "' (allowed: " + list + ")");
    }
  }
}

void ConfigReader::Finish() const {
  if (problems_.empty()) return;
  std::vector<std::string> messages;
  for (const auto& [position, message] : problems_) messages.push_back(message);
  throw ConfigError(messages);
}

}  // namespace canalid::sim
