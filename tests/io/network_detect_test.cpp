// Issue 40 point 10: a network file's format comes from its real root
// element (markup inside a leading comment, a processing instruction or a
// doctype is none), and DynaML attributes geoanchor does not read are
// refused by name, never ignored.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "temp_folder.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;
const fs::path kNetworks = fs::path(GEOANCHOR_SOURCE_DIR) / "fixtures" / "networks";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(NetworkDetect, Issue40_TheFormatComesFromTheRealRootElement) {
  const std::string gama = "<gama-local xmlns=\"http://www.gnu.org/software/gama/gama-local\"><network/></gama-local>\n";
  const std::string prologues[] = {
      "",
      "<?xml version=\"1.0\" ?>\n<!-- field book: <obs from=\"1\"> re-keyed; see <direction> notes -->\n",
      "<?xml version=\"1.0\"?><?xml-stylesheet href=\"<obs>\"?>\n",
      "<!DOCTYPE gama-local [ <!ENTITY obs \"<obs>\"> ]>\n<!-- a > b -->\n",
  };
  for (const auto& p : prologues) {
    EXPECT_EQ(detect_network_format(p + gama, "n.xml"), NetworkFormat::gama_local) << p;
    EXPECT_EQ(detect_network_format(p + "<DnaXmlFormat type=\"Station File\"/>", "n.xml"), NetworkFormat::dynaml) << p;
  }
  try {
    detect_network_format("<!-- <gama-local> -->\n<obs/>", "n.xml");
    ADD_FAILURE() << "an XML file whose root is <obs> was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("root element is <obs>"), std::string::npos) << e.what();
  }
}

TEST(NetworkDetect, Issue40_DynamlStationAndMeasurementAttributesAreRefusedByName) {
  testing::TempFolder dir;
  const std::string stn = slurp(kNetworks / "dynadjust" / "gnss-networkstn.xml");
  const std::string msr = slurp(kNetworks / "dynadjust" / "gnss-networkmsr.xml");
  struct Case {
    std::string station, measurement, attribute;
  };
  std::string stn_attr = stn, msr_attr = msr;
  stn_attr.replace(stn_attr.find("<DnaStation>"), 12, "<DnaStation unused=\"yes\">");
  msr_attr.replace(msr_attr.find("<DnaMeasurement>"), 16, "<DnaMeasurement ignore=\"*\">");
  for (const Case& c : {Case{stn_attr, msr, "unused=\"yes\""}, Case{stn, msr_attr, "ignore=\"*\""}}) {
    std::ofstream(dir.path() / "stn.xml", std::ios::binary) << c.station;
    std::ofstream(dir.path() / "msr.xml", std::ios::binary) << c.measurement;
    try {
      read_network({(dir.path() / "stn.xml").string(), (dir.path() / "msr.xml").string()});
      ADD_FAILURE() << c.attribute << " was ignored";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "E_DYNAML") << e.what();
      EXPECT_NE(std::string(e.what()).find("attribute " + c.attribute + " is not read"), std::string::npos) << e.what();
    }
  }
  // The files as published read.
  std::ofstream(dir.path() / "stn.xml", std::ios::binary) << stn;
  std::ofstream(dir.path() / "msr.xml", std::ios::binary) << msr;
  EXPECT_NO_THROW(read_network({(dir.path() / "stn.xml").string(), (dir.path() / "msr.xml").string()}));
}

}  // namespace
}  // namespace geoanchor::io
