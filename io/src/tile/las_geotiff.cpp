#include "geoanchor/io/tile/las_geotiff.hpp"

namespace geoanchor::io {
namespace {

constexpr std::uint16_t kKeyDirectory = 34735;  // GeoKeyDirectoryTag
constexpr std::uint16_t kDoubleParams = 34736;  // GeoDoubleParamsTag
constexpr std::uint16_t kAsciiParams = 34737;   // GeoAsciiParamsTag

}  // namespace

std::optional<LasGeoKeys> las_geotiff_crs(const std::vector<LasVlr>& vlrs, const std::string& where, bool set_aside_unread) {
  const LasVlr* directory = nullptr;
  const LasVlr* doubles = nullptr;  // the values of double-valued keys
  const LasVlr* ascii = nullptr;    // citations
  for (const auto& v : vlrs) {
    if (v.user_id != "LASF_Projection") continue;
    if (v.record_id == kKeyDirectory) directory = &v;
    if (v.record_id == kDoubleParams) doubles = &v;
    if (v.record_id == kAsciiParams) ascii = &v;
  }
  if (!directory) return std::nullopt;
  return geotiff_crs(GeoKeyRecords{directory->data, doubles ? &doubles->data : nullptr, ascii ? &ascii->data : nullptr},
                     where, set_aside_unread);
}

}  // namespace geoanchor::io
