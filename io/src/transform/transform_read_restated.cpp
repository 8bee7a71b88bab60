// The keys of a transform file that state its transform again (format
// version, EPSG method, PROJ pipeline, the other convention's alternative)
// or say where it came from: type-checked, and held to the model read.

#include <cmath>
#include <string>
#include <variant>

#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "transform/transform_common.hpp"

namespace geoanchor::io::detail {
namespace {

// alternatives[i].parameters are written as the exact negation of the
// rotations at full precision; 1e-9 (m, ″, ppm) allows a re-spelling in mm,
// mas or ppb.
constexpr double kAlternativeTol = 1e-9;

}  // namespace

// Keys that describe the transform again (for PROJ, EPSG, the other
// convention) or say where it came from: type-checked, and where they state
// the convention or the parameters a second time, held to the first.
void check_written_keys(const json& doc, const TransformFile& t, std::string_view source) {
  const std::string model(to_string(t.model));
  if (const json* v = member(doc, "format_version")) {
    if (!v->is_number_integer() || v->get<long long>() != 1) {
      fail(source, "format_version", "value " + v->dump() + " not read by this geoanchor, which reads format 1");
    }
  }
  for (const char* key : {"description", "generator", "proj_pipeline", "wkt2"}) {
    if (const json* v = member(doc, key)) string_at(*v, key, source);
  }
  if (const json* v = member(doc, "projjson")) {
    if (!v->is_object()) fail(source, "projjson", "value is not a JSON object");
  }
  if (const json* v = member(doc, "epsg_method")) {
    const std::string stated = string_at(*v, "epsg_method", source);
    const std::string expected = epsg_method(t);
    if (expected.empty()) {
      fail(source, "epsg_method",
           "value \"" + stated + "\": no EPSG method describes model " + model +
               (t.rotation_model == geodesy::RotationModel::exact
                    ? " with rotation_model exact (EPSG's Helmert methods are the small-angle formulas): the file states "
                      "its rotation model twice, differently; correct one"
                    : "; remove it"));
    }
    if (stated != expected) {
      fail(source, "epsg_method",
           "value \"" + stated + "\" contradicts model " + model + " in convention " + std::string(t.convention_name()) +
               " (" + expected + "): the file states its method twice, differently; correct one");
    }
  }
  // The file's own PROJ pipeline, as written, must be the one its model,
  // convention, rotation model and parameters give (an edited
  // rotation_model was applied without a word: issue 40 point 10).
  if (const json* v = member(doc, "proj_pipeline")) {
    const std::string stated = string_at(*v, "proj_pipeline", source);
    if (const auto diff = pipeline_difference(stated, proj_pipeline(t))) {
      fail(source, "proj_pipeline",
           "contradicts the file's model, convention, rotation_model and parameters (" + *diff +
               "): the file states its transform twice, differently; correct one (or remove proj_pipeline)");
    }
  }
  const json* alts = member(doc, "alternatives");
  if (!alts) return;
  if (t.enu_origin || t.site_calibration) {
    fail(source, "alternatives", "not read for model " + model + ": it has no other rotation convention; remove it");
  }
  if (!alts->is_array()) fail(source, "alternatives", "value is not an array");
  const TransformFile other = swapped_convention(t);
  const std::string other_convention(other.convention_name());
  for (std::size_t i = 0; i < alts->size(); ++i) {
    const std::string where = "alternatives[" + std::to_string(i) + "]";
    const json& a = (*alts)[i];
    only_keys(a, where, source, {"convention", "epsg_method", "parameters", "proj_pipeline", "wkt2", "projjson"});
    if (!a.contains("convention")) fail(source, where + ".convention", "missing");
    const std::string c = string_at(a.at("convention"), where + ".convention", source);
    if (c != other_convention) {
      fail(source, where + ".convention",
           "value \"" + c + "\" is not the other convention of convention " + std::string(t.convention_name()) +
               "; the file states its convention twice, differently: correct one (or remove alternatives)");
    }
    if (const json* e = member(a, "epsg_method")) {
      const std::string stated = string_at(*e, where + ".epsg_method", source);
      if (epsg_method(other).empty()) {
        fail(source, where + ".epsg_method", "value \"" + stated + "\": no EPSG method describes the exact rotation model");
      }
      if (stated != epsg_method(other)) {
        fail(source, where + ".epsg_method", "value \"" + stated + "\" is not " + epsg_method(other) + ", the method of " +
                                                 other_convention);
      }
    }
    for (const char* key : {"proj_pipeline", "wkt2"}) {
      if (const json* v = member(a, key)) string_at(*v, where + "." + key, source);
    }
    if (const json* v = member(a, "projjson")) {
      if (!v->is_object()) fail(source, where + ".projjson", "value is not a JSON object");
    }
    if (const json* params = member(a, "parameters")) {
      // The same transform in the other convention: read as a transform
      // file of its own, then compared parameter by parameter.
      json alt = {{"model", doc.at("model")}, {"convention", c}, {"parameters", *params}};
      for (const char* key : {"rotation_model", "reference_epoch"}) {
        if (doc.contains(key)) alt[key] = doc.at(key);
      }
      ModelParameters unused;
      const TransformFile read = parse_transform_doc(alt, std::string(source) + ": " + where, unused);
      const json got = std::visit([](const auto& h) { return parameters_json(h); }, read.helmert);
      const json want = std::visit([](const auto& h) { return parameters_json(h); }, other.helmert);
      for (const auto& [key, value] : want.items()) {
        const double g = got.at(key).get<double>(), w = value.get<double>();
        if (!(std::fabs(g - w) <= kAlternativeTol)) {
          fail(source, where + ".parameters." + key,
               "value " + format_shortest(g) + " is not the " + other_convention + " form (" + format_shortest(w) +
                   ") of parameters; the file states its parameters twice, differently: correct one (or remove "
                   "alternatives)");
        }
      }
      if (read.pivot_m && t.pivot_m && !((*read.pivot_m - *t.pivot_m).norm() <= kAlternativeTol)) {
        fail(source, where + ".parameters.px_m", "the pivot differs from parameters'");
      }
    }
  }
}

}  // namespace geoanchor::io::detail
