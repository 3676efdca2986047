#pragma once
#include <string>
#include <string_view>

#include "sim/canal.h"
#include "sim/config_reader.h"

namespace canalid::sim {

/// Loads a canal description from TOML (format and every key: docs/canalsim.md and
/// config/sim/asce-canal2.toml).  @throws ConfigError listing every problem with file:line:column.
Canal LoadCanal(const std::string& path);
/// Parses `text` as LoadCanal parses a file's contents; messages name the file `name`.
/// @throws ConfigError listing every problem with name:line:column.
Canal ParseCanal(std::string_view text, const std::string& name);

/// Reads the keys of a `structure` table into `structure` (keys absent keep their value).
void ReadStructure(ConfigReader& reader, const toml::table& table, const std::string& where,
                   Structure* structure);
/// Reads the keys of an `offtake` table into `offtake` (keys absent keep their value).
void ReadOfftake(ConfigReader& reader, const toml::table& table, const std::string& where,
                 Offtake* offtake);

}  // namespace canalid::sim
