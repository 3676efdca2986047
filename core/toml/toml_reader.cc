#include "core/toml/toml_reader.h"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace canalid::core {
namespace {

std::string JoinIssues(const std::vector<TomlIssue>& issues) {
  std::string out;
  for (const TomlIssue& issue : issues) out += (out.empty() ? "" : "\n") + issue.ToString();
  return out;
}

int OneBased(toml::source_index index) { return index == 0 ? 1 : static_cast<int>(index); }

}  // namespace

std::string TomlIssue::ToString() const {
  std::string out = file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": ";
  if (!path.empty()) out += path + ": ";
  return out + message;
}

TomlError::TomlError(std::vector<TomlIssue> issues)
    : std::runtime_error(JoinIssues(issues)), issues_(std::move(issues)) {}

TomlReader::TomlReader(std::string_view text, std::string name) : name_(std::move(name)) {
  try {
    root_ = toml::parse(text, name_);
  } catch (const toml::parse_error& e) {
    TomlIssue issue;
    issue.file = name_;
    issue.line = OneBased(e.source().begin.line);
    issue.column = OneBased(e.source().begin.column);
    issue.message = std::string(e.description());
    throw TomlError({issue});
  }
}

TomlReader TomlReader::FromFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  if (in) text << in.rdbuf();
  if (!in) {
    TomlIssue issue;
    issue.file = path;
    issue.message = "cannot read the file";
    throw TomlError({issue});
  }
  return TomlReader(text.str(), path);
}

void TomlReader::Problem(const toml::source_region& where, std::string path, std::string message) {
  TomlIssue issue;
  issue.file = name_;
  issue.line = OneBased(where.begin.line);
  issue.column = OneBased(where.begin.column);
  issue.path = std::move(path);
  issue.message = std::move(message);
  issues_.push_back(std::move(issue));
}

std::vector<TomlIssue> TomlReader::Issues() const {
  // Problems are found table by table, not line by line: give them in the file's order.
  std::vector<TomlIssue> sorted = issues_;
  std::stable_sort(sorted.begin(), sorted.end(), [](const TomlIssue& a, const TomlIssue& b) {
    return std::pair(a.line, a.column) < std::pair(b.line, b.column);
  });
  return sorted;
}

void TomlReader::Mark(const std::string& path, const toml::source_region& where) {
  positions_.emplace(path, where);
}

toml::source_region TomlReader::Locate(std::string path) const {
  while (!path.empty()) {
    const auto it = positions_.find(path);
    if (it != positions_.end()) return it->second;
    // "reach[0].level" -> "reach[0]" -> "reach" -> "" (the file's start).
    const std::size_t dot = path.rfind('.');
    const std::size_t bracket = path.rfind('[');
    std::size_t cut = 0;
    if (dot != std::string::npos) cut = dot;
    if (bracket != std::string::npos && (dot == std::string::npos || bracket > dot)) cut = bracket;
    path.resize(cut);
  }
  return toml::source_region{};
}

std::vector<std::pair<std::string, toml::source_region>> TomlReader::UnknownKeys(
    const toml::table& table, std::initializer_list<std::string_view> allowed) {
  std::vector<std::pair<std::string, toml::source_region>> unknown;
  for (const auto& [key, node] : table) {
    if (std::find(allowed.begin(), allowed.end(), key.str()) == allowed.end()) {
      unknown.emplace_back(std::string(key.str()), key.source());
    }
  }
  return unknown;
}

std::string TomlKeyPath(std::string_view where, std::string_view key) {
  return where.empty() ? std::string(key) : std::string(where) + "." + std::string(key);
}

const char* TomlTypeName(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    default:
      return "a date or time";
  }
}

std::string JoinNames(std::initializer_list<std::string_view> names, std::string_view quote) {
  std::string out;
  for (std::string_view name : names) {
    out += (out.empty() ? "" : ", ") + std::string(quote) + std::string(name) + std::string(quote);
  }
  return out;
}

}  // namespace canalid::core
