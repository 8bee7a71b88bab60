#pragma once
// The datum of a network adjustment: the translations, rotations and scale
// as motions of the unknowns, which combinations of them the measurements
// and constraints leave undefined or define only weakly (judged against the
// network's own precision, datum_rank.hpp), and how the datum is held, in
// words. A free network's inner constraints and S-transformation are
// network_free_datum.hpp's.
//
// Private to solver.

#include <Eigen/Core>

#include <string>
#include <vector>

#include "network_problem.hpp"

namespace geoanchor::solver {

// The datum parameters as motions of the unknowns, each scaled to move the
// stations by 1 m RMS: translations along X, Y, Z (x, y, z), rotations
// about X, Y, Z through the centroid (local: about the vertical), scale.
struct DatumVectors {
  Eigen::MatrixXd g;  // u × d
  std::vector<std::string> names;
  // The columns of g over the named motions (identity unless some
  // combination of them moves nothing, e.g. a rotation about the line
  // through the only two stations: such combinations are no datum).
  Eigen::MatrixXd basis;
  Eigen::MatrixXd named;  // u × (named motions): each named motion, unit RMS (g = named · basis)
};

DatumVectors datum_vectors(const NetworkProblem& p, const UnknownLayout& layout);

// Names a combination over the datum parameters by its largest parts.
std::string name_combination(const Eigen::VectorXd& e, const std::vector<std::string>& names);

// The datum, judged against the network's own precision
// (datum_information): what the measurements and the constraints
// leave undefined of the translations, rotations and scale. A
// station the measurements do not fix on its own is no datum
// defect but a singularity (check_station_blocks, network_singularity.hpp).
// Sets the defect the constraints leave (p.defect, its motions and names;
// held by the input's datum stations when it has them, else refused), the
// inner-constraint stations' check and anchors (a free network), and
// `datum_warnings`: the combinations defined only weakly.
void define_datum(NetworkProblem& p, std::vector<std::string>& datum_warnings, int jobs);

// How the datum is defined, in words (AdjustmentResult::datum).
std::string datum_in_words(const NetworkProblem& p);

}  // namespace geoanchor::solver
