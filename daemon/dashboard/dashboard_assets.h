#pragma once
#include <span>
#include <string_view>

namespace canalid::dashboard {

/// A file of the page, embedded at build time (embed_assets.cmake): the page itself and
/// Debian's libjs-dygraphs.  The dashboard serves these and nothing else from disk.
struct Asset {
  std::string_view path;  ///< as requested, e.g. "/assets/dashboard.js"
  std::string_view content_type;
  std::string_view body;
};

/// Every embedded asset (generated).
std::span<const Asset> Assets();

/// The asset at `path` (exact match), or nullptr.
const Asset* FindAsset(std::string_view path);

}  // namespace canalid::dashboard
