#pragma once
// The CSV columns of a CRS's coordinates (docs/conventions.md, "Columns of
// a CRS"). Each column names its quantity and the axis's unit:
//
//   geographic   lat_<u>, lon_<u>           u: deg, grad
//   projected    easting_<u>, northing_<u>  u: m, ft (international foot), ftus (US survey foot), km
//   geocentric   x_m, y_m, z_m
//   heights      h_<u> ellipsoidal, H_<u> orthometric (the vertical CRS of a compound CRS)
//
// "easting" is the axis PROJ's proj_normalize_for_visualization puts first
// and "northing" the other, whatever their names and directions (Japan's
// X north / Y east, LAEA Europe, UPS), with the CRS's own numbers.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/crs/crs.hpp"

namespace geoanchor::io {

struct CrsColumns {
  Crs crs;  // the CRS as the columns use it: a 2-D CRS promoted to 3-D for h_<u>, a frame's geocentric CRS for x_m
  // Column names in PROJ's visualisation order (the order CrsOperation
  // takes): longitude or easting, latitude or northing, then the height.
  std::vector<std::string> names;
  std::vector<bool> angular;  // per name: an angle (formatted with the degrees' decimals)
  // The order columns are written in, as indices into `names`: latitude
  // before longitude (as every geoanchor output writes them), else as named.
  std::vector<std::size_t> write_order;
  bool has_height() const { return names.size() == 3; }
  bool orthometric = false;  // the height is H_<u>
};

// The columns `crs` is read from in `header` (`flag` names where the CRS
// came from, `source` the file). Throws geoanchor::Error (input, E_COLUMN)
// naming both the column and the CRS for a header that disagrees with the
// CRS: a coordinate column in another unit than the axis ("easting_m" for
// a CRS in US survey feet), of another kind (lat_deg for a projected CRS),
// missing, given twice, an orthometric height without a vertical CRS, an
// ellipsoidal one for a compound CRS, a 3-D CRS without its height, or an
// epoch or utm_zone column (the CRS@EPOCH and the CRS say those).
// With a `role` ("src", "dst": a control set's two frames) the role goes
// before the unit, as in every control-set column: easting_src_ftus,
// lat_dst_deg, H_src_m; an epoch column is then the set's own, not refused.
CrsColumns crs_input_columns(const Crs& crs, const std::vector<std::string>& header, std::string_view source,
                             std::string_view flag, std::string_view role = {});

// The columns `crs` is written to. `with_height`: the input carries a
// height (a 2-D CRS is then promoted to 3-D); `geocentric`: --to ecef.
// Throws geoanchor::Error (usage) for a CRS that needs a height the input
// does not have (a height is never invented).
CrsColumns crs_output_columns(const Crs& crs, bool with_height, bool geocentric, std::string_view flag);

// Header indices of `columns.names` in `header`, in the same order.
std::vector<std::size_t> column_indices(const CrsColumns& columns, const std::vector<std::string>& header);

// Those columns as CoordinateColumns (which header columns are coordinates),
// for io::output_header.
CoordinateColumns coordinate_columns_at(const std::vector<std::size_t>& indices);

// The names `columns` are written under, in their write order.
std::vector<std::string> written_names(const CrsColumns& columns);

// What geoanchor understood of the CRS as JSON (schema geoanchor.crs/1,
// docs/commands/crs.md): the description's fields, the columns it is read
// from and written to, and its WKT2:2019.
std::string crs_json_text(const Crs& crs);

}  // namespace geoanchor::io
