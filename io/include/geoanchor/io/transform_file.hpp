#pragma once
// The transform file: the JSON that `geoanchor fit` writes and `convert` /
// `apply` read. Schema: docs/transform-file.md.
//
//   {"model": "helmert7" | "helmert6" | "translation3" | "helmert14",
//    "convention": "position_vector" | "coordinate_frame",
//    "rotation_model": "small_angle" | "exact",
//    "source_frame": "ITRF2014@2010.0", "target_frame": "GDA2020",
//    "reference_epoch": 2010.0,
//    "parameters": {"tx_m", "ty_m", "tz_m", "rx_arcsec", "ry_arcsec",
//                   "rz_arcsec", "ds_ppm", and for helmert14 the rates
//                   "dtx_m_per_year", ..., "drx_arcsec_per_year", ...,
//                   "dds_ppm_per_year"}}
//
// Every parameter key carries its unit; mm, mas and ppb spellings are read
// too (tx_mm, rx_mas, ds_ppb, dtx_mm_per_year, drx_mas_per_year,
// dds_ppb_per_year). A parameter given twice in two units, a missing
// convention, a helmert14 without reference_epoch, a missing parameter and
// any unknown key are errors naming the file and the key.

#include <filesystem>
#include <optional>
#include <string>
#include <variant>

#include "geoanchor/geodesy/affine.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/helmert.hpp"

namespace geoanchor::io {

enum class TransformModel { helmert7, helmert6, translation3, helmert14 };
std::string_view to_string(TransformModel m);

struct TransformFile {
  TransformModel model = TransformModel::helmert7;
  geodesy::RotationModel rotation_model = geodesy::RotationModel::small_angle;
  // 7-parameter models hold a Helmert7, helmert14 a Helmert14; the
  // convention is the alternative's type.
  std::variant<geodesy::Helmert7<geodesy::PositionVector>, geodesy::Helmert7<geodesy::CoordinateFrame>,
               geodesy::Helmert14<geodesy::PositionVector>, geodesy::Helmert14<geodesy::CoordinateFrame>>
      helmert;
  std::optional<geodesy::Frame> source_frame;
  std::optional<geodesy::Frame> target_frame;
  std::optional<geodesy::DecimalYear> reference_epoch;  // required for helmert14

  bool time_dependent() const { return model == TransformModel::helmert14; }
  std::string_view convention_name() const;

  // target_from_source in ECEF at `observation_epoch`. Throws
  // geoanchor::Error (input) if the transform is time-dependent and no epoch
  // is given; `where` names what lacks it (a file:line, a flag).
  geodesy::AffineMap target_from_source(std::optional<geodesy::DecimalYear> observation_epoch,
                                        std::string_view where) const;
};

// Throws geoanchor::Error (io for an unreadable file, input for the rest).
TransformFile read_transform_file(const std::filesystem::path& path);
TransformFile parse_transform_json(std::string_view text, std::string_view source_name);

// The file's JSON text (parameters in m, arcsec, ppm and their rates).
std::string to_json_text(const TransformFile& t);

}  // namespace geoanchor::io
