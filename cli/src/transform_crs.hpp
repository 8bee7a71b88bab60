#pragma once
// `geoanchor transform` with CRSs in --from/--to (issue 13): the catalog
// frame a CRS is on, and a row's coordinates read and written through PROJ.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/io/control/coordinate_codec.hpp"
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/io/control/crs_columns.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/io/csv.hpp"

namespace geoanchor::cli {

// Whether a --from/--to text is a CRS for PROJ (EPSG:n, WKT, PROJJSON, a
// PROJ string, @FILE) rather than a frame name of the catalog.
bool is_crs_text(const std::string& text);

// The catalog frame a CRS is on, with the CRS's coordinate epoch.
geodesy::Frame catalog_frame_of(const io::Crs& crs, const char* flag);

// A row's coordinates in a CRS read through PROJ, to and from ECEF on the
// CRS's datum: the columns the CRS names (docs/commands/convert.md), PROJ's
// conversion to its geocentric CRS, and back on the output side.
class CrsRows {
 public:
  CrsRows(const io::Crs& source, const io::Crs& target, const std::vector<std::string>& header,
          const std::string& source_name, io::NumberFormat numbers);
  const io::CoordinateColumns& coordinates() const { return coordinates_; }
  geodesy::EcefPosition decode(const io::CsvRecord& r, const std::vector<std::string>& header, const std::string& source,
                               const std::string& where);
  std::vector<std::string> encode(const geodesy::EcefPosition& p, const std::string& where);
  std::vector<std::string> warnings() const;
  const io::CrsColumns& input() const { return in_; }
  const io::CrsColumns& output() const { return out_; }
  // PROJ's operations at both ends, as the sidecar records them.
  nlohmann::json operations_json() const;

 private:
  io::CrsColumns in_, out_;
  io::CrsOperation to_ecef_, from_ecef_;
  std::vector<std::size_t> index_;
  io::CoordinateColumns coordinates_;
  io::NumberFormat numbers_;
};

}  // namespace geoanchor::cli
