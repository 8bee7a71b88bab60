#pragma once
// What adjust's outputs share (private to workflow's adjust): how a
// measurement is named and scaled in the CSVs and the report, and the
// estimated Helmert in the transform file's units.

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <numbers>
#include <ostream>
#include <string>
#include <vector>

#include "geoanchor/workflow/adjust.hpp"

namespace geoanchor::workflow::adjust_detail {

inline constexpr double kRadToDeg = 180.0 / std::numbers::pi;
inline constexpr double kRadToArcsec = 648000.0 / std::numbers::pi;

// A measurement kind's key in the CSVs and the JSON report.
std::string kind_key(geodesy::MeasurementKind k);

// Whether a measurement kind is an angle (radians; degrees and arcseconds
// in the outputs).
bool angular(geodesy::MeasurementKind k);

// The stations a measurement names: "A->B" (from, to), "A->B C->D" for
// baselines, "A B C" for a point cluster or an observation set (each once,
// in the order its parts name them).
std::string stations_of(const geodesy::Network& net, const geodesy::NetworkMeasurement& m);

// A CSV field, quoted where it holds a comma, quote or line break.
std::string csv_field(const std::string& v);

// A measurement's metadata as the measurements CSV's `metadata` column
// writes it: key=value pairs joined by ';', each '%', ';', '=' and line
// break inside a key or value written as %25, %3B, %3D, %0A, %0D (so the
// pairs split back exactly); "" for none.
std::string metadata_text(const geodesy::NetworkMeasurement& m);

// Within [−1, 1] (rounding of a nearly dependent pair can put it a few
// parts in 10⁶ outside); 0 where a component is fixed (σ = 0).
double correlation(const Eigen::Matrix3d& c, int a, int b);

// The estimated Helmert in the transform file's units (m, arcsec, ppm and
// per year) and convention (rotations negated for coordinate_frame).
struct HelmertInFileUnits {
  std::vector<std::string> names;
  Eigen::VectorXd value;
  Eigen::MatrixXd covariance;
};

HelmertInFileUnits helmert_in_file_units(const PreparedNetwork& prepared, const solver::AdjustmentResult& r);

// The relative precision's section of the text report (the worst pairs)
// and the standard's verdicts (counts, the worst margin), from
// adjust_relative.cpp.
void relative_report_text(std::ostream& out, const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                          const solver::AdjustOptions& o);
// The JSON report's `relative_pairs` (which pairs, how many), `relative`
// (each pair; full detail only) and `standard` (with --standard).
void relative_report_document(nlohmann::ordered_json& j, const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                              const solver::AdjustOptions& o, bool full);

}  // namespace geoanchor::workflow::adjust_detail
