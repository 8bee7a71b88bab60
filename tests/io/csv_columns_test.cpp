// CSV splitting and what a header says about its coordinates.

#include <gtest/gtest.h>

#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/io/csv.hpp"

namespace geoanchor::io {
namespace {

std::vector<std::string> split(const std::string& header) {
  std::vector<std::string> raw, values;
  split_csv_line(header, raw, values, "t");
  return values;
}

std::string error_of(const std::string& header) {
  try {
    classify_coordinate_header(split(header), "points.csv");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Csv, SplitsQuotedFieldsAndKeepsTheRawText) {
  std::vector<std::string> raw, values;
  split_csv_line(R"(P1,"Runway 16, threshold","say ""hi""",,x)", raw, values, "t");
  ASSERT_EQ(values.size(), 5u);
  EXPECT_EQ(values[1], "Runway 16, threshold");
  EXPECT_EQ(raw[1], "\"Runway 16, threshold\"");
  EXPECT_EQ(values[2], "say \"hi\"");
  EXPECT_EQ(values[3], "");
  EXPECT_THROW(split_csv_line("a,\"open", raw, values, "t"), Error);
  EXPECT_EQ(csv_quote("a,b"), "\"a,b\"");
  EXPECT_EQ(csv_quote("plain"), "plain");
}

TEST(Csv, ReaderKeepsCommentsAndChecksFieldCounts) {
  std::istringstream in("# first\r\nid,x_m\r\n\r\n# mid\r\nP1,1\r\nP2,2,3\r\n");
  CsvReader reader(in, "f.csv");
  EXPECT_EQ(reader.leading_comments(), std::vector<std::string>{"# first"});
  EXPECT_EQ(reader.header(), (std::vector<std::string>{"id", "x_m"}));
  CsvRecord r;
  ASSERT_TRUE(reader.next(r));
  EXPECT_TRUE(r.is_comment);
  ASSERT_TRUE(reader.next(r));
  EXPECT_EQ(r.values[1], "1");
  EXPECT_EQ(r.line, 5u);
  try {
    reader.next(r);
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "f.csv:6: 3 fields; expected 2 as in the header (line 2)");
  }
}

// issue 12 point 12
TEST(Csv, Point12_CrOnlyAndMixedLineEndsAreLinesAsLf) {
  const std::string lf = "# first\nid,x_m\n\n# mid\nP1,1\nP2,2\nP3,3,4\n";
  for (const std::string ends : {"\r", "\r\n", "mixed"}) {
    std::string text;
    int k = 0;
    for (const char c : lf) {
      if (c != '\n') {
        text += c;
      } else if (ends == "mixed") {
        static const char* const kEnds[] = {"\r", "\r\n", "\n"};  // never a CR just before an LF end
        text += kEnds[k++ % 3];
      } else {
        text += ends;
      }
    }
    std::istringstream in(text);
    CsvReader reader(in, "f.csv");
    EXPECT_EQ(reader.leading_comments(), std::vector<std::string>{"# first"}) << ends;
    EXPECT_EQ(reader.header(), (std::vector<std::string>{"id", "x_m"})) << ends;
    CsvRecord r;
    ASSERT_TRUE(reader.next(r)) << ends;
    EXPECT_TRUE(r.is_comment);
    EXPECT_EQ(r.comment, "# mid");
    ASSERT_TRUE(reader.next(r)) << ends;
    EXPECT_EQ(r.values, (std::vector<std::string>{"P1", "1"})) << ends;
    EXPECT_EQ(r.line, 5u) << ends;
    ASSERT_TRUE(reader.next(r)) << ends;
    EXPECT_EQ(r.values, (std::vector<std::string>{"P2", "2"})) << ends;
    EXPECT_EQ(r.line, 6u) << ends;
    try {
      reader.next(r);
      ADD_FAILURE() << ends << ": the 3-field line was read";
    } catch (const Error& e) {
      EXPECT_STREQ(e.what(), "f.csv:7: 3 fields; expected 2 as in the header (line 2)") << ends;
    }
  }
}

// issue 12 point 12
TEST(Csv, Point12_TextThatIsNotUtf8IsRefusedNamingLineFieldAndByte) {
  std::istringstream in("id,x_m\nP1,1\nP\xE9,2\n");
  CsvReader reader(in, "f.csv");
  CsvRecord r;
  ASSERT_TRUE(reader.next(r));
  try {
    reader.next(r);
    ADD_FAILURE() << "the Latin-1 id was read";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_CSV_NOT_UTF8");
    EXPECT_NE(std::string(e.what()).find("f.csv:3: id 'P\\xE9' is not valid UTF-8 (byte 2 of the line is 0xE9)"),
              std::string::npos)
        << e.what();
  }
  // UTF-8 "Pé" is read as it is.
  std::istringstream ok("id,x_m\nP\xC3\xA9,2\n");
  CsvReader utf8(ok, "g.csv");
  ASSERT_TRUE(utf8.next(r));
  EXPECT_EQ(r.values[0], "P\xC3\xA9");
}

// issue 12 point 15
TEST(Csv, Point15_TabOrSemicolonHeaderIsRefusedNamingTheSeparator) {
  for (const auto& [text, seen] : {std::pair<std::string, std::string>{"id\tx_m\ty_m\n", "tabs"},
                                   std::pair<std::string, std::string>{"id;x_m;y_m\n", "semicolons (';')"}}) {
    std::istringstream in(text);
    try {
      CsvReader reader(in, "f.csv");
      ADD_FAILURE() << seen << ": the header was read";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "E_CSV_SEPARATOR");
      EXPECT_NE(std::string(e.what()).find("f.csv:1: the header is separated by " + seen + ", not commas"), std::string::npos)
          << e.what();
    }
  }
}

TEST(CoordinateColumns, RecognisesEachKindAndPassesAttributesThrough) {
  const auto g = classify_coordinate_header(split("id,lon_deg,lat_deg,h_m,n_returns,epoch"), "f");
  EXPECT_EQ(g.kind, CoordinateKind::geodetic);
  EXPECT_EQ(g.first, 2u);  // lat, whatever its position
  EXPECT_EQ(g.second, 1u);
  EXPECT_EQ(*g.third, 3u);
  EXPECT_EQ(*g.epoch, 5u);
  EXPECT_FALSE(g.is_coordinate(4));
  EXPECT_EQ(classify_coordinate_header(split("x_m,y_m,z_m"), "f").kind, CoordinateKind::ecef);
  EXPECT_EQ(classify_coordinate_header(split("e_m,n_m,u_m"), "f").kind, CoordinateKind::enu);
  const auto ned = classify_coordinate_header(split("n_m,e_m,d_m"), "f");
  EXPECT_EQ(ned.kind, CoordinateKind::ned);
  EXPECT_EQ(ned.first, 0u);
  EXPECT_EQ(classify_coordinate_header(split("easting_m,northing_m,utm_zone"), "f").kind, CoordinateKind::projected);
  EXPECT_FALSE(classify_coordinate_header(split("lat_deg,lon_deg"), "f").third.has_value());
  const auto src = classify_coordinate_header(split("id,lat_src_deg,lon_src_deg,h_src_m,x_dst_m"), "f", "src");
  EXPECT_EQ(src.kind, CoordinateKind::geodetic);
}

TEST(CoordinateColumns, AnOrthometricHeightIsTheThirdGeodeticOrProjectedColumn) {
  const auto c = classify_coordinate_header({"id", "lat_deg", "lon_deg", "H_m"}, "points.csv");
  EXPECT_EQ(c.kind, CoordinateKind::geodetic);
  EXPECT_TRUE(c.orthometric);
  EXPECT_EQ(c.third, 3u);
  const auto p = classify_coordinate_header({"easting_m", "northing_m", "H_m"}, "points.csv");
  EXPECT_TRUE(p.orthometric);
  EXPECT_FALSE(classify_coordinate_header({"lat_deg", "lon_deg", "h_m"}, "points.csv").orthometric);
}

TEST(CoordinateColumns, RefusesMixedMissingUnknownAndOrthometricColumns) {
  EXPECT_EQ(error_of("lat_deg,lon_deg,x_m,y_m,z_m"),
            "points.csv: header mixes coordinate kinds (lat/lon and x/y/z); expected the columns of exactly one kind");
  EXPECT_EQ(error_of("id,lat_deg,h_m"),
            "points.csv: header has lat/lon columns but no lon_deg; expected lat_deg,lon_deg,h_m");
  EXPECT_NE(error_of("lat_rad,lon_deg").find("header column 1 'lat_rad': unit 'rad' is not read"), std::string::npos);
  EXPECT_NE(error_of("lat,lon").find("header column 1 'lat': coordinate column without a unit"), std::string::npos);
  EXPECT_NE(error_of("lat_deg,lon_deg,H_ft").find("'H_ft': orthometric height without its unit; expected H_m"), std::string::npos);
  EXPECT_NE(error_of("lat_deg,lon_deg,h_m,H_m").find("an ellipsoidal (h) and an orthometric (H) height in one header"),
            std::string::npos);
  EXPECT_NE(error_of("x_m,y_m,z_m,H_m").find("'H_m': does not belong with x/y/z coordinates"), std::string::npos);
  EXPECT_NE(error_of("LAT_DEG,lon_deg").find("case-sensitive; expected lat_deg"), std::string::npos);
  EXPECT_NE(error_of("e_m,n_m,u_m,d_m").find("mixes ENU (u) and NED (d)"), std::string::npos);
  EXPECT_NE(error_of("x_m,y_m,z_m,x_m").find("appears twice"), std::string::npos);
  EXPECT_NE(error_of("id,name").find("header names no coordinates"), std::string::npos);
  EXPECT_NE(error_of("x_m,y_m,z_m,h_m").find("does not belong with x/y/z coordinates"), std::string::npos);
}

}  // namespace
}  // namespace geoanchor::io
