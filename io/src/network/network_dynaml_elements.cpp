// DynaML's elements as the reader meets them: each where DynaML.xsd puts it,
// without attributes (anything else refused by name), and their text kept
// by tag until their station or measurement ends.

#include <array>
#include <bitset>
#include <initializer_list>
#include <optional>
#include <set>
#include <string>

#include "geoanchor/crs/frame_ellipsoid.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "network/network_dynaml_reader.hpp"

namespace geoanchor::io::detail::dynaml {

void Reader::set_root(const std::string& frame_name, const std::string& epoch_text, std::size_t at, const std::string& what) {
  frame_name_ = frame_name;
  epoch_text_ = epoch_text;
  if (root_warnings_ && (frame_name_.empty() || epoch_text_.empty())) {
    net_.warnings.push_back(source_ + ": " + what + " names no " +
                            std::string(frame_name_.empty() ? "reference frame" : "epoch") +
                            ": DynaML.xsd's default (GDA2020, 01.01.2020) applies");
  }
  root_frame_ = frame_of(frame_name_.empty() ? "GDA2020" : frame_name_, epoch_text_.empty() ? "01.01.2020" : epoch_text_, at, what);
  if (!net_.frame) {
    net_.frame = root_frame_;
    // The frame's ellipsoid: the catalog's, else PROJ's (AGD66: the
    // Australian National Spheroid); unknown, adjust refuses the network.
    if (const auto e = frame_ellipsoid(*root_frame_, where(at) + ": " + what + " reference frame")) {
      net_.ellipsoid = e->ellipsoid;
      net_.ellipsoid_stated = true;
      geocentric_ = geodesy::GeocentricConverter(net_.ellipsoid);
    }
  }
}

void Reader::start(const std::string& name, const XML_Char** attributes) {
  text_.clear();
  const Tag tag = tag_of(name);
  const Tag parent = path_.empty() ? Tag::other : path_.back();
  path_.push_back(tag);
  if (path_.size() == 1) {
    if (name != "DnaXmlFormat") fail(line(), "root element <" + name + ">; expected <DnaXmlFormat>");
    root_seen_ = true;
    for (const XML_Char** a = attributes; *a; a += 2) {
      const std::string key = a[0], value = a[1];
      if (key == "referenceframe") frame_name_ = value;
      else if (key == "epoch") epoch_text_ = value;
      else if (key != "type" && key != "xmlns:xsi" && key != "xsi:noNamespaceSchemaLocation") {
        fail(line(), "<DnaXmlFormat> attribute " + key + "=\"" + value +
                         "\" is not read by geoanchor; expected type, referenceframe, epoch");
      }
    }
    set_root(frame_name_, epoch_text_, line(), "<DnaXmlFormat>");
    return;
  }
  if (path_.size() == 2) {
    // DynaML.xsd gives <DnaStation> and <DnaMeasurement> no attributes:
    // one would go unread (issue 40 point 10).
    if (*attributes && (tag == Tag::DnaStation || tag == Tag::DnaMeasurement)) {
      fail(line(), "<" + name + "> attribute " + std::string(attributes[0]) + "=\"" + attributes[1] +
                       "\" is not read by geoanchor (DynaML.xsd gives <" + name + "> no attributes)");
    }
    if (tag == Tag::DnaStation) {
      station_.clear();
      station_.line = line();
      in_station_ = true;
    } else if (tag == Tag::DnaMeasurement) {
      measurement_.clear();
      measurement_.line = line();
      in_measurement_ = true;
    } else {
      fail(line(), "element <" + name + "> in <DnaXmlFormat>; expected <DnaStation> or <DnaMeasurement>");
    }
    return;
  }
  // Every element where DynaML.xsd puts it, without attributes; anything
  // else is refused by name, never skipped.
  using Children = std::bitset<kTagCount>;
  static const std::array<std::optional<Children>, kTagCount> kChildren = [] {
    std::array<std::optional<Children>, kTagCount> c;
    const auto set = [&](Tag of, std::initializer_list<Tag> children) {
      Children b;
      for (Tag t : children) b.set(static_cast<std::size_t>(t));
      c[static_cast<std::size_t>(of)] = b;
    };
    using enum Tag;
    set(DnaStation, {Name, Constraints, Type, StationCoord, Description});
    set(StationCoord, {Name, XAxis, YAxis, Height, HemisphereZone});
    set(DnaMeasurement, {Type, Ignore, ReferenceFrame, Epoch, First, Second, Third, Value, StdDev, InstHeight, TargHeight, Total,
                         Directions, Vscale, Pscale, Lscale, Hscale, GPSBaseline, Clusterpoint, Coords, Source, MeasurementID,
                         ClusterID});
    set(GPSBaseline, {X, Y, Z, MeasurementID, SigmaXX, SigmaXY, SigmaXZ, SigmaYY, SigmaYZ, SigmaZZ, GPSCovariance});
    set(Clusterpoint, {X, Y, Z, MeasurementID, SigmaXX, SigmaXY, SigmaXZ, SigmaYY, SigmaYZ, SigmaZZ, PointCovariance});
    set(GPSCovariance, {m11, m12, m13, m21, m22, m23, m31, m32, m33});
    set(PointCovariance, {m11, m12, m13, m21, m22, m23, m31, m32, m33});
    set(Directions, {Ignore, Target, Value, StdDev, MeasurementID});
    return c;
  }();
  const auto& allowed = kChildren[static_cast<std::size_t>(parent)];
  if (!allowed) fail(line(), "element <" + name + "> inside <" + name_of(parent) + ">, which holds a value, not elements");
  if (!allowed->test(static_cast<std::size_t>(tag))) {
    std::set<std::string> names;  // in the order of their bytes
    for (std::size_t k = 0; k < kTagCount; ++k) {
      if (allowed->test(k)) names.insert(std::string(kTagNames[k]));
    }
    std::string list;
    for (const auto& k : names) list += (list.empty() ? "" : ", ") + k;
    fail(line(), "element <" + name + "> in <" + name_of(parent) + "> is not read by geoanchor; expected one of " + list);
  }
  if (*attributes) {
    fail(line(), "<" + name + "> attribute " + std::string(attributes[0]) + "=\"" + attributes[1] + "\" is not read by geoanchor");
  }
  if (in_measurement_ && tag == Tag::GPSBaseline) {
    Measurement& m = measurement_;
    Item& item = m.items.push();
    item.line = line();
    if (!m.firsts.empty()) item.first = m.firsts.back();
    if (!m.seconds.empty()) item.second = m.seconds.back();
  } else if (in_measurement_ && tag == Tag::Clusterpoint) {
    Measurement& m = measurement_;
    Item& item = m.items.push();
    item.line = line();
    if (!m.firsts.empty()) item.first = m.firsts.back();
  } else if (in_measurement_ && (tag == Tag::GPSCovariance || tag == Tag::PointCovariance)) {
    if (measurement_.items.empty()) fail(line(), "<" + name + "> outside a baseline or cluster point");
    measurement_.items.back().blocks.push();
  } else if (in_measurement_ && tag == Tag::Directions && path_.size() == 3) {
    measurement_.directions.push().line = line();
  }
}

void Reader::end(const std::string& name) {
  // The element's text, trimmed, viewed in text_ (cleared on the way out).
  struct ClearText {
    std::string& t;
    ~ClearText() { t.clear(); }
  } clear_text{text_};
  const std::string_view value = trim(text_);
  const std::size_t depth = path_.size();
  const Tag tag = path_.back();
  const Tag parent = depth >= 2 ? path_[depth - 2] : Tag::other;
  path_.pop_back();
  if (depth == 2) {
    if (tag == Tag::DnaStation) finish_station();
    if (tag == Tag::DnaMeasurement) finish_measurement();
    in_station_ = in_measurement_ = false;
    return;
  }
  // A value given twice is refused (First and Second repeat in clusters).
  auto put = [&](Fields& into) {
    if (!into.emplace(tag, value)) fail(line(), "<" + name + "> given twice in <" + name_of(parent) + ">");
  };
  using enum Tag;
  if (in_station_) {
    if (parent == DnaStation && tag != StationCoord) put(station_.fields);
    else if (parent == StationCoord) put(station_.coord);
    return;
  }
  if (!in_measurement_) return;
  Measurement& m = measurement_;
  if (parent == DnaMeasurement) {
    if (tag == First) m.firsts.push().assign(value);
    if (tag == Second) m.seconds.push().assign(value);
    if (tag != GPSBaseline && tag != Clusterpoint && tag != Directions) {
      if (tag == First || tag == Second) {
        m.fields.emplace(tag, value);  // the first one (clusters repeat them)
      } else {
        put(m.fields);
      }
    }
  } else if (parent == GPSBaseline || parent == Clusterpoint) {
    if (tag != GPSCovariance && tag != PointCovariance) put(m.items.back().fields);
  } else if (parent == GPSCovariance || parent == PointCovariance) {
    put(m.items.back().blocks.back());
  } else if (parent == Directions) {
    put(m.directions.back().fields);
  }
}

}  // namespace geoanchor::io::detail::dynaml
