#pragma once
// NGS GNSS Vector Exchange (GVX) 1.0, between its two halves (private to
// io): network_gvx.cpp streams the XML through expat into records of typed,
// checked leaves; network_gvx_records.cpp turns the records into stations
// and GNSS baselines. docs/network-format.md lists what each element means
// and where it goes.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/network.hpp"

namespace geoanchor::io::detail::gvx {

// One element holding text, by its path below its record
// ("QUALITY_CONTROL/DILUTION_PRECISION/PDOP"), its text (trimmed; checked
// against the schema's type) and the line of its start tag. An element
// written empty (<CODE/>, as NGS's own writer leaves optional ones) is no
// leaf: absent.
struct Leaf {
  std::string path;
  std::string text;
  std::size_t line = 0;
};

// One child of <GVX>: SOURCE_DATA, PROJECT_INFORMATION, REFERENCE_SYSTEM,
// EQUIPMENT, SURVEY_SETUP, POINT, GNSS_VECTOR, or the file's REMARK (a
// record of one leaf whose path is empty).
struct Record {
  std::string type;
  std::size_t line = 0;
  std::vector<Leaf> leaves;

  // The leaf at `path`, or nullptr.
  const Leaf* find(std::string_view path) const;
  // Its text, or "" when absent.
  const std::string& text(std::string_view path) const;
};

// The whole file's records, in the file's order.
struct Document {
  std::vector<Record> records;
};

// A GVX date and time (xs:dateTime, "must be in GPS time": YYYY-MM-DDThh:mm:ss
// with optional decimals and an optional Z, no other zone) in seconds since
// the GPS epoch 1980-01-06T00:00:00; nullopt for anything else or a day
// that does not exist.
std::optional<double> gps_seconds_of(std::string_view date_time);
// Days from 0001-01-01 to the date (proleptic Gregorian); nullopt for a
// date that does not exist.
std::optional<long> days_from_civil(int year, int month, int day);

// Streams `text` into records (throws geoanchor::Error, input, E_GVX, naming
// the source, the line, the element and what was expected for anything the
// schema does not have or a value of the wrong type).
Document parse_document(std::string_view text, const std::string& source);

// The records into `net` (stations defined free, one gnss_baselines
// measurement per vector); throws as parse_document for a reference to no
// record, a frame geoanchor cannot reach, a covariance that is not
// positive definite, …
void read_records(const Document& doc, const std::string& source, geodesy::Network& net);

}  // namespace geoanchor::io::detail::gvx
