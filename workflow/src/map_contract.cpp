#include "geoanchor/workflow/map_contract.hpp"

namespace geoanchor::workflow {

using T = io::MapMetadataBuilder::Text;

void check_survey_against_input(const io::SurveyMetadata& survey, const io::TileMetadata& in, const std::string& in_source,
                                const std::string& artifact) {
  io::MapMetadataBuilder b(artifact);
  io::tile_contract_fields(b, in, "the input (" + in_source + ")");
  if (in.metadata) {
    const io::MapMetadata& m = *in.metadata;
    if (m.enu_origin && !in.coordinates.origin) b.enu_origin(*m.enu_origin, "the input's metadata");
    if (m.enu_origin_source) b.text(T::enu_origin_source, *m.enu_origin_source, "the input's metadata");
    if (m.vertical_datum) b.text(T::vertical_datum, *m.vertical_datum, "the input's metadata");
  }
  b.survey(survey, true);
}

io::MapMetadata output_map_metadata(const io::TileMetadata& out, const io::TileMetadata& in, const std::string& in_source,
                                    const std::optional<std::array<double, 2>>& epoch_range,
                                    const std::optional<std::array<std::uint64_t, 7>>& solution_counts,
                                    const io::SurveyMetadata* survey, const std::string& artifact) {
  io::MapMetadataBuilder b(artifact);
  const std::string derived = "the output's coordinates";
  // The output's own keys, but not the share: that is the input's, stated below.
  io::TileMetadata own = out;
  own.rtk_fixed_percent.reset();
  io::tile_contract_fields(b, own, derived);
  if (epoch_range) b.coordinate_epoch_range(*epoch_range, "the points' GPS times");
  if (solution_counts) {
    geodesy::SolutionCounts c;
    c.count = *solution_counts;
    b.gnss_solution_counts(c, "computed from the extra bytes 'gnss_solution' of " + std::to_string(c.total()) +
                                  " points of the input");
  }
  // The same frame (name and epoch): what holds in the input's frame holds here.
  const bool same_frame = in.frame && out.frame && in.frame->name() == out.frame->name() &&
                          in.frame->epoch().has_value() == out.frame->epoch().has_value() &&
                          (!in.frame->epoch() || in.frame->epoch()->year == out.frame->epoch()->year);
  const bool origin_kept = in.coordinates.origin && out.coordinates.origin && out.origin_source == in.origin_source;
  const std::string in_who = "the input (" + in_source + ")";
  if (in.rtk_fixed_percent) b.rtk_fixed_percent(*in.rtk_fixed_percent, in_who + ": survey.rtk_fixed_percent", false);
  if (in.metadata) {
    const io::MapMetadata& m = *in.metadata;
    const std::string who = in_who + ": metadata";
    if (m.gnss_method) b.text(T::gnss_method, *m.gnss_method, who);
    if (m.gnss_base) b.text(T::gnss_base, *m.gnss_base, who);
    if (m.geoid_model) b.text(T::geoid_model, *m.geoid_model, who);
    if (m.gnss_solution_counts) b.gnss_solution_counts(*m.gnss_solution_counts, who);
    if (m.rtk_fixed_percent && !m.gnss_solution_counts) b.rtk_fixed_percent(*m.rtk_fixed_percent, who, false);
    if (same_frame && m.enu_origin && (!out.coordinates.origin || origin_kept)) b.enu_origin(*m.enu_origin, who);
    if (m.enu_origin_source && (origin_kept || (same_frame && !out.coordinates.origin))) {
      b.text(T::enu_origin_source, *m.enu_origin_source, who);
    }
  }
  if (survey) b.survey(*survey, same_frame && (!out.coordinates.origin || origin_kept));
  return b.metadata();
}

}  // namespace geoanchor::workflow
