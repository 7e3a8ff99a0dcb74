#include "core/file_io.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "core/error.hpp"
#include "core/yaml_io.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab {
namespace {

std::string utf8_error(std::string_view text) {
  try {
    require_utf8(text, "f.txt");
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

// The well-formed byte sequences of Unicode's Table 3-7, and one of each way to break them.
TEST(Utf8, AcceptsEveryWellFormedSequenceAndNamesTheFirstBadByte) {
  EXPECT_EQ(utf8_error("plain ASCII\n"), "");
  EXPECT_EQ(utf8_error("\xC3\xA9t\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x8C\x8A \xF4\x8F\xBF\xBF"), "");
  EXPECT_EQ(utf8_error("line 1\nab\x9A"), "f.txt:2:3: got byte 0x9A, expected UTF-8 text");
  EXPECT_NE(utf8_error("\xC0\x80"), "");          // overlong NUL
  EXPECT_NE(utf8_error("\xE0\x80\xAF"), "");      // overlong '/'
  EXPECT_NE(utf8_error("\xED\xA0\x80"), "");      // a surrogate, U+D800
  EXPECT_NE(utf8_error("\xF4\x90\x80\x80"), "");  // past U+10FFFF
  EXPECT_NE(utf8_error("\xE2\x82"), "");          // cut short
  EXPECT_NE(utf8_error("\xF5\x80\x80\x80"), "");  // never a lead byte
  EXPECT_EQ(utf8_error("\xE2\x82\xAC\xFF"), "f.txt:1:2: got byte 0xFF, expected UTF-8 text");
}

// Latin-1 text would reach metrics.json (scenario names, baseline descriptions), whose JSON
// writer refuses it mid-run: every reader refuses it up front instead.
TEST(Utf8, EveryReaderOfTextRefusesLatin1) {
  const auto dir = test::fresh_temp_dir("utf8");
  std::ofstream(dir / "s.yaml", std::ios::binary) << "name: caf\xE9\n";
  try {
    read_text_file(dir / "s.yaml", "scenario file");
    ADD_FAILURE() << "Latin-1 accepted";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml:1:10: got byte 0xE9, expected UTF-8 text"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(yaml::load_string("name: caf\xE9\n", "t.yaml"), UserError);
  EXPECT_THROW(yaml::override_document("name=caf\xE9"), UserError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace driftlab
