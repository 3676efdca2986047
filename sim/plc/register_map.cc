#include "sim/plc/register_map.h"

#include <algorithm>

namespace canalid::sim::plc {

int InputRegisterCount(const PlcConfig& config) {
  const int n = static_cast<int>(config.pools.size());
  return std::max({kIrSystemSize, config.input_scaled_base + n * kPoolInputFields,
                   config.input_float_base + 2 * n * kPoolInputFields});
}

int HoldingRegisterCount(const PlcConfig& config) {
  const int n = static_cast<int>(config.pools.size());
  return std::max({kHrSystemSize, config.holding_scaled_base + n * kPoolHoldingFields,
                   config.holding_float_base + 2 * n * kPoolHoldingFields});
}

double StructureUnit(const PlcConfig& config, Structure::Type type) {
  return type == Structure::Type::kPump ? config.flow_unit_m3s : config.setting_unit_m;
}

double OfftakeUnit(const PlcConfig& config, Offtake::Type type) {
  return type == Offtake::Type::kOrifice ? config.area_unit_m2 : config.flow_unit_m3s;
}

}  // namespace canalid::sim::plc
