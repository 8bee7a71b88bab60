#include "geoanchor/workflow/transform_checks.hpp"

#include <variant>

#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::workflow {

std::vector<std::string> implausible_transform_warnings(const io::TransformFile& t, std::string_view transform_name,
                                                        std::optional<EpochSpan> epochs_of_use) {
  std::vector<std::string> out;
  const std::string name(transform_name);
  switch (t.model) {
    case io::TransformModel::enu_origin:
    case io::TransformModel::site_calibration:
      return out;  // a local map's placement: see the header
    case io::TransformModel::helmert14: {
      if (!epochs_of_use) return out;
      std::vector<geodesy::DecimalYear> ends{epochs_of_use->first};
      if (!(epochs_of_use->last == epochs_of_use->first)) ends.push_back(epochs_of_use->last);
      for (const geodesy::DecimalYear at : ends) {
        std::visit(
            [&](const auto& h) {
              if constexpr (requires { h.reference_epoch; }) {
                for (auto& w : geodesy::implausible_parameter_warnings(geodesy::evaluate_at(h, at))) {
                  out.push_back(name + " at epoch " + format_shortest(at.year) + ": " + w);
                }
              }
            },
            t.helmert);
      }
      return out;
    }
    case io::TransformModel::helmert7:
    case io::TransformModel::helmert6:
    case io::TransformModel::translation3:
    case io::TransformModel::molodensky_badekas:
      std::visit(
          [&](const auto& h) {
            if constexpr (!requires { h.reference_epoch; }) {
              for (auto& w : geodesy::implausible_parameter_warnings(h)) out.push_back(name + ": " + w);
            }
          },
          t.helmert);
      return out;
  }
  return out;
}

}  // namespace geoanchor::workflow
