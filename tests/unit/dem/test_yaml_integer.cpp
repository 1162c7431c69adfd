// Config integers (Section::integer, every YAML tool's counts and intervals): read from their text
// exactly, not through a double, and refused outside their range with the real bounds in the
// message (docs/cli.md#numbers-in-config-files).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <climits>
#include <string>

#include "tomodem/core/error.hpp"
#include "tomodem/dem/yaml_fields.hpp"

using tomodem::InputError;
using tomodem::yaml::Section;

namespace {
Section section(const std::string& yaml) { return Section(YAML::Load(yaml), "", "c.yaml"); }

// The message of the InputError that reading `n` throws ("" when none).
std::string refusal(const std::string& value, long min = 0, long max = LONG_MAX / 2) {
  try {
    section("n: " + value).integer("n", 0, min, max);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

// 2^53 + 1 went through a double and came back as 2^53, without a word.
TEST(YamlInteger, WholeNumbersAbove2To53AreExact) {
  EXPECT_EQ(section("n: 9007199254740993").integer("n", 0), 9007199254740993L);
  EXPECT_EQ(section("n: 4611686018427387903").integer("n", 0), LONG_MAX / 2);
  EXPECT_EQ(section("n: -9223372036854775808").integer("n", 0, LONG_MIN, 0), LONG_MIN);
  EXPECT_EQ(section("n: +12").integer("n", 0), 12);
  EXPECT_EQ(section("n: 010").integer("n", 0), 10);  // decimal, as the double reading gave
  // Other forms of a whole number, where a double holds them exactly.
  EXPECT_EQ(section("n: 1e3").integer("n", 0), 1000);
  EXPECT_EQ(section("n: 1000.0").integer("n", 0), 1000);
  EXPECT_EQ(section("{}").integer("n", 7), 7);
}

// The message said "[0, 10^18]" for a limit of 2^62 - 1 (LONG_MAX / 2): it now states the range
// that applies, and a number past any long is refused, not clamped.
TEST(YamlInteger, OutOfRangeNamesTheRealRange) {
  std::string m = refusal("4611686018427387904");
  EXPECT_NE(m.find("c.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("4611686018427387904"), std::string::npos) << m;
  EXPECT_NE(m.find("[0, 4611686018427387903]"), std::string::npos) << m;
  EXPECT_EQ(m.find("10^18"), std::string::npos) << m;
  m = refusal("99999999999999999999");
  EXPECT_NE(m.find("not clamped"), std::string::npos) << m;
  m = refusal("-1", 1, 100);
  EXPECT_NE(m.find("[1, 100]"), std::string::npos) << m;
  m = refusal("101", 1, 100);
  EXPECT_NE(m.find("[1, 100]"), std::string::npos) << m;
  // Beyond 2^53 in another form: a double no longer holds every whole number there.
  m = refusal("1e16");
  EXPECT_NE(m.find("write it in digits"), std::string::npos) << m;
  EXPECT_NE(refusal("2.5").find("whole number"), std::string::npos);
  EXPECT_NE(refusal("abc").find("number"), std::string::npos);
}
