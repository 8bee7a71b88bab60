#pragma once
// A fit as the files and text a geodesist keeps: the transform file that
// `geoanchor fit -o` writes and the workbench's "Save transform…" writes
// (the same function, so the two cannot drift), the printed fit report
// (`fit` and `report`), and the reverse: the fit choices a transform file
// records, so that the workbench can reopen a saved fit.

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::workflow {

// What a point left out by the user is noted as in the transform file's
// per-point records; fit_choices_from_transform() reads it back.
inline constexpr const char* kLeftOutInWorkbench = "left out in the workbench";

// The statistics a transform file records of the adjustment that gave it
// (fit's, or adjust --estimate-helmert's): σ0, dof, the significance
// levels and the global test.
void record_statistics(io::FitRecord& f, std::optional<double> sigma0, int dof, double alpha, double alpha_point,
                       const solver::GlobalTest& global_test);

// The transform file for `fit` of `control` under `options` (alpha,
// alpha_point recorded). `left_out` names points the user left out: their
// records say so. `generator` is recorded as is ("geoanchor 0.1.0: ...").
// The file carries the map metadata contract (transform_metadata below,
// with `survey` when given) and, for a set with GNSS solution types, their
// counts (gnss_solutions) and each mark's type.
io::TransformFile transform_file_from_fit(const solver::FitResult& fit, const geodesy::ControlSet& control,
                                          const solver::FitOptions& options, const std::vector<std::string>& left_out,
                                          const std::string& generator, const io::SurveyMetadata* survey = nullptr);

// The same file with its per-point records formed from `fit` as
// io::write_json(out, file, points) writes them: `geoanchor fit` on 10⁶
// marks never holds them all. `fit` must outlive `points`; `control` is
// read here only.
struct StreamedTransformFile {
  io::TransformFile file;  // its fit record holds no points
  io::PointRecordSource points;
};
StreamedTransformFile streamed_transform_file_from_fit(const solver::FitResult& fit, const geodesy::ControlSet& control,
                                                       const solver::FitOptions& options,
                                                       const std::vector<std::string>& left_out,
                                                       const std::string& generator, const io::SurveyMetadata* survey = nullptr);
// (A temporary fit would be gone before its records are written.)
StreamedTransformFile streamed_transform_file_from_fit(solver::FitResult&& fit, const geodesy::ControlSet& control,
                                                       const solver::FitOptions& options,
                                                       const std::vector<std::string>& left_out,
                                                       const std::string& generator,
                                                       const io::SurveyMetadata* survey = nullptr) = delete;

// A fit with the control network's extent its transform file records (the
// hull, in the source frame, of the marks the fit used): fit_helmert(control,
// options), the extent of the marks to be used formed meanwhile on another
// core (the solve runs on one; at 10⁶ marks the extent is 0.1 s of the
// command). Where the fit used other marks than those (data snooping removed
// some), the extent is formed again from the marks it used: it is always the
// one streamed_transform_file_from_fit(fit, ...) forms. The extent holds
// for `control` as given and for the marks fit.points[i].used names: neither
// may change before the file is formed.
struct FitForExport {
  solver::FitResult fit;
  std::optional<io::ControlExtent> extent;  // none when the fit used no mark
};
FitForExport fit_for_export(const geodesy::ControlSet& control, const solver::FitOptions& options);
// streamed_transform_file_from_fit(fitted.fit, ...) with fitted.extent.
StreamedTransformFile streamed_transform_file_from_fit(const FitForExport& fitted, const geodesy::ControlSet& control,
                                                       const solver::FitOptions& options,
                                                       const std::vector<std::string>& left_out,
                                                       const std::string& generator, const io::SurveyMetadata* survey = nullptr);
StreamedTransformFile streamed_transform_file_from_fit(FitForExport&& fitted, const geodesy::ControlSet& control,
                                                       const solver::FitOptions& options,
                                                       const std::vector<std::string>& left_out,
                                                       const std::string& generator,
                                                       const io::SurveyMetadata* survey = nullptr) = delete;

// The map metadata contract of a fit's transform file: the target frame
// and epoch, the horizontal CRS and vertical datum of the target
// coordinates (the geoid of orthometric ones), the nominal origin of an
// enu-origin or site-calibration fit, the RTK-fixed share and counts from
// the set's GNSS solution types, the storage; the rest from `survey`.
// Throws geoanchor::Error (E_METADATA_CONFLICT) where `survey` contradicts
// what the fit derives.
io::MapMetadata transform_metadata(const solver::FitResult& fit, const geodesy::ControlSet& control,
                                   const io::SurveyMetadata* survey);

// The GNSS solution types of `control`'s marks under options.solutions:
// per class the marks, those the fit used, those left out for their type.
// nullopt for a set without solution types.
std::optional<io::GnssSolutionRecord> solution_record(const solver::FitResult& fit, const geodesy::ControlSet& control,
                                                      const solver::FitOptions& options);

// The report `geoanchor fit` prints: parameters with σ, σ0, the global test
// with its verdict, and the residual table, flagged points first.
void write_fit_report(std::ostream& out, const solver::FitResult& fit, const geodesy::ControlSet& control,
                      const solver::FitOptions& options);

// The choices a transform file records: model, convention, rotation model,
// reference epoch, pivot, nominal origin (enu-origin, site-calibration),
// site grid, alpha, alpha_point, scaling by σ0, data snooping's removals
// (a mark removed by it: the fit was made with --remove-outliers), and the
// points left out in the workbench. A file without a fit record (published parameters) gives
// its model and convention with the default statistics settings.
struct FitChoices {
  solver::FitOptions options;
  std::vector<std::string> left_out;
};
FitChoices fit_choices_from_transform(const io::TransformFile& t);

}  // namespace geoanchor::workflow
