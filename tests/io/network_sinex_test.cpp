// SINEX parameter indices (issue 40 point 7, found by fuzz/sinex_fuzz.cpp):
// INDEX, PARA1 and PARA2 are 5-digit fields; a value past 99999 that still
// reads as a whole number (9e99 in INDEX's five columns, a matrix value
// shifted into PARA2) was cast to std::size_t, undefined behaviour
// (UBSan: "outside the range of representable values"). It is refused by
// line, naming the field.

#include <gtest/gtest.h>

#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/network/network_input.hpp"

namespace geoanchor::io {
namespace {

// One site's X, Y, Z and their covariance (SINEX 2.02 fixed columns).
std::string sinex(const std::string& first_index, const std::string& first_matrix_line) {
  return "%=SNX 2.02 GAN 24:184:00000 GAN 24:184:00000 24:184:00000 C 00003 2 S\n"
         "+SOLUTION/ESTIMATE\n"
         "*INDEX TYPE__ CODE PT SOLN _REF_EPOCH__ UNIT S __ESTIMATED VALUE____ _STD_DEV___\n"
         " " + first_index + " STAX   REFA  A    1 24:184:00000 m    2 0.427083187719317E+07 0.10000E-02\n"
         "     2 STAY   REFA  A    1 24:184:00000 m    2 0.638475891331886E+06 0.10000E-02\n"
         "     3 STAZ   REFA  A    1 24:184:00000 m    2 0.467892768006842E+07 0.10000E-02\n"
         "-SOLUTION/ESTIMATE\n"
         "+SOLUTION/MATRIX_ESTIMATE L COVA\n" +
         first_matrix_line + "\n"
         "     2     1  0.00000000000000E+00  1.00000000000000E-06\n"
         "     3     1  0.00000000000000E+00  0.00000000000000E+00  1.00000000000000E-06\n"
         "-SOLUTION/MATRIX_ESTIMATE L COVA\n"
         "%ENDSNX\n";
}

std::string error_of(const std::string& text) {
  NetworkReadOptions o;
  o.sinex_frame = geodesy::Frame::parse("ITRF2014", "test");
  geodesy::Network net;
  try {
    read_network_text(text, "s.snx", net, o);
  } catch (const Error& e) {
    return e.code() + ": " + e.what();
  }
  return "";
}

TEST(NetworkSinex, Issue40_AnIndexPast99999IsRefusedByLine) {
  const std::string matrix = "     1     1  1.00000000000000E-06";
  ASSERT_EQ(error_of(sinex("    1", matrix)), "");
  EXPECT_EQ(error_of(sinex(" 9e99", matrix)), "E_SINEX: s.snx:4: INDEX 9e99 must be a whole number from 1 to 99999");
  EXPECT_EQ(error_of(sinex("    1", "     1   467510978022946E+07  1.00000000000000E-06")),
            "E_SINEX: s.snx:9: PARA1 and PARA2 must be whole numbers from 1 to 99999 (parameter indices)");
  EXPECT_EQ(error_of(sinex("    1", "  1e300     1  1.00000000000000E-06")),
            "E_SINEX: s.snx:9: PARA1 and PARA2 must be whole numbers from 1 to 99999 (parameter indices)");
}

}  // namespace
}  // namespace geoanchor::io
