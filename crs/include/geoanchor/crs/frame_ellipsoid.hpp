#pragma once
// The ellipsoid a frame's or a CRS's geodetic coordinates are on: from
// geoanchor's frame catalog, else from PROJ's database (the EPSG dataset's
// ellipsoid of the geodetic CRS or datum of that name). Never a default: a
// network's heights, local horizons and ellipsoid arcs are on it, and GRS 80
// in place of International 1924 moves a point by up to 250 m.

#include <optional>
#include <string>
#include <string_view>

#include "geoanchor/crs/crs.hpp"
#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/frame.hpp"

namespace geoanchor::io {

struct FrameEllipsoid {
  geodesy::Ellipsoid ellipsoid;
  // Where it came from, for notes and messages: "geoanchor's frame
  // catalog", or "PROJ: EPSG:4272 'NZGD49'".
  std::string source;
};

// The ellipsoid of frame `f`:
//  - a frame of geoanchor's catalog (WGS84, ITRF, ETRF, NAD83, GDA…):
//    geodesy::implied_ellipsoid;
//  - any other name: the geodetic CRSs and geodetic datums of PROJ's
//    database whose name or alias is that name (compared as PROJ compares
//    names exactly: any letter case), also with a space between its letters
//    and a trailing year ("Pulkovo1942": "Pulkovo 1942"; Frame::parse drops
//    spaces) and with a year 19YY written YY ("NZGD1949": "NZGD49",
//    "OSGB1936": "OSGB36"). Deprecated entries are left out. When they name
//    one ellipsoid, that one.
// nullopt when neither knows the name. Throws geoanchor::Error (input,
// E_ELLIPSOID) naming `where` when PROJ's entries of that name lie on
// different ellipsoids (the name does not say which).
//
// The ellipsoid is one of geodesy::named_ellipsoid's when a and 1/f agree
// with it to 1e-12 relative (PROJ's and geoanchor's definitions of the same
// EPSG ellipsoid, so that a stated "Clarke 1866" equals NAD27's), else
// custom with PROJ's a, 1/f and name.
std::optional<FrameEllipsoid> frame_ellipsoid(const geodesy::Frame& f, std::string_view where);

// The ellipsoid of a CRS (geographic, geocentric, projected or compound:
// its geodetic datum's), as frame_ellipsoid gives it: named when PROJ's a
// and 1/f are a named ellipsoid's.
geodesy::Ellipsoid crs_ellipsoid(const Crs& crs);

// Whether two ellipsoids are the same within what a definition's digits
// carry: a within 0.1 mm, 1/f within 1e-9 relative (b within 0.02 mm).
bool same_ellipsoid(const geodesy::Ellipsoid& x, const geodesy::Ellipsoid& y);

}  // namespace geoanchor::io
