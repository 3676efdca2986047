#pragma once
#include <nlohmann/json.hpp>
#include <string>

namespace canalid::testing {

/// The JSON after `marker` on a log line (a discarded value when the line has no marker or the
/// rest does not parse).
inline nlohmann::json JsonAfter(const std::string& line, const std::string& marker) {
  const std::size_t at = line.find(marker);
  if (at == std::string::npos) return {};
  return nlohmann::json::parse(line.substr(at + marker.size()), nullptr, false);
}

}  // namespace canalid::testing
