#include "daemon/dashboard/dashboard_assets.h"

namespace canalid::dashboard {

const Asset* FindAsset(std::string_view path) {
  for (const Asset& asset : Assets()) {
    if (asset.path == path) return &asset;
  }
  return nullptr;
}

}  // namespace canalid::dashboard
