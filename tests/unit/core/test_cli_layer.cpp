// The shared command-line layer (docs/cli.md): the length parser, the summary builder's common
// keys, where a summary goes, the duration text of progress lines, and random seeds.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/progress.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/units.hpp"

namespace fs = std::filesystem;

TEST(Lengths, UnitsScaleToMetres) {
  // 1 mm = 1e-3 m, 1 um = 1e-6 m, 1 nm = 1e-9 m (SI prefixes); a bare number is metres.
  EXPECT_DOUBLE_EQ(tomodem::parse_length("--x", "60.7um"), 60.7e-6);
  EXPECT_DOUBLE_EQ(tomodem::parse_length("--x", "60.7\xc2\xb5m"), 60.7e-6);
  EXPECT_DOUBLE_EQ(tomodem::parse_length("--x", "0.05mm"), 5e-5);
  EXPECT_DOUBLE_EQ(tomodem::parse_length("--x", "0.05MM"), 5e-5);
  EXPECT_DOUBLE_EQ(tomodem::parse_length("--x", "2 nm"), 2e-9);
  EXPECT_DOUBLE_EQ(tomodem::parse_length("--x", "1e-3"), 1e-3);
  EXPECT_DOUBLE_EQ(tomodem::parse_length("--x", "-1.5m"), -1.5);
}

TEST(Lengths, UnknownUnitsAndNonNumbersNameTheOption) {
  for (const char* bad : {"3km", "3 furlong", "mm", "", "nan", "1e999"}) {
    try {
      tomodem::parse_length("--grip", bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const tomodem::InputError& e) {
      EXPECT_EQ(e.field(), "--grip") << bad;
      EXPECT_EQ(e.value(), bad);
    }
  }
}

// Seeds are read from their text over the whole of [0, 2^64 - 1]: never through a double (2^53 + 1
// was read as 2^53), never clamped (2^64 became 2^63 - 1 or 2^64 - 1) or wrapped (-1).
TEST(Seeds, WholeRangeExactlyAndNothingElse) {
  EXPECT_EQ(tomodem::parse_seed("", "--seed", "0"), 0u);
  EXPECT_EQ(tomodem::parse_seed("", "--seed", "+7"), 7u);
  EXPECT_EQ(tomodem::parse_seed("", "--seed", "1e3"), 1000u);
  EXPECT_EQ(tomodem::parse_seed("", "--seed", "9007199254740993"), 9007199254740993u);
  EXPECT_EQ(tomodem::parse_seed("", "--seed", "18446744073709551615"), 18446744073709551615u);
  for (const char* bad : {"18446744073709551616", "99999999999999999999", "-1", "-4", "1.5", "abc", "", "1e20",
                          "9007199254740993.0", "nan", "inf", "0x"}) {
    try {
      tomodem::parse_seed("c.yaml", "seed (line 2)", bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const tomodem::InputError& e) {
      EXPECT_EQ(e.file(), "c.yaml") << bad;
      EXPECT_EQ(e.field(), "seed (line 2)") << bad;
      EXPECT_EQ(e.value(), bad);
      EXPECT_NE(e.why().find("2^64 - 1"), std::string::npos) << e.what();
    }
  }
}

TEST(Summary, OwnsTheCommonKeys) {
  tomodem::Summary s("tomodem-test");
  s.input("in.h5", {{"format", "h5"}});
  s.output("packing", "out.h5");
  s.output("nothing", "");  // an empty path is no output
  s.n_particles(42);
  s.unit("E", "Pa");
  s["E"] = 1e9;
  const auto j = nlohmann::json::parse(s.text());
  EXPECT_EQ(j["tool"], "tomodem-test");
  EXPECT_EQ(j["input"]["path"], "in.h5");
  EXPECT_EQ(j["input"]["format"], "h5");
  EXPECT_EQ(j["outputs"].size(), 1u);
  EXPECT_EQ(j["outputs"]["packing"], "out.h5");
  EXPECT_EQ(j["n_particles"], 42);
  EXPECT_EQ(j["units"]["E"], "Pa");
  EXPECT_EQ(j["units"]["wall_time_s"], "s");
  EXPECT_EQ(j["E"], 1e9);
  EXPECT_GE(j["wall_time_s"].get<double>(), 0);
  EXPECT_GE(j["cpu_time_s"].get<double>(), 0);
  EXPECT_GT(j["peak_rss_bytes"].get<double>(), 0);
  for (const char* k : {"version", "git_hash", "command_line", "host", "utc_time"})
    EXPECT_TRUE(j["provenance"].contains(k)) << k;
}

TEST(Summary, WithoutAnInputThePathIsNull) {
  const auto j = nlohmann::json::parse(tomodem::Summary("tomodem-test").text());
  EXPECT_TRUE(j["input"]["path"].is_null());
  EXPECT_TRUE(j["outputs"].is_object());
}

TEST(Summary, JsonFileIsWrittenAndDashIsNoFile) {
  const fs::path dir = fs::path(::testing::TempDir()) / "summary_emit";
  fs::create_directories(dir);
  const fs::path f = dir / "s.json";
  tomodem::emit_summary("{\"a\": 1}\n", f.string());
  std::ifstream in(f);
  std::stringstream t;
  t << in.rdbuf();
  EXPECT_EQ(t.str(), "{\"a\": 1}\n");
  const fs::path cwd = fs::current_path();
  fs::current_path(dir);
  testing::internal::CaptureStdout();
  tomodem::emit_summary("{\"b\": 2}\n", "-");
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "{\"b\": 2}\n");
  EXPECT_FALSE(fs::exists(dir / "-"));
  fs::current_path(cwd);
}

TEST(Progress, DurationsReadAsMinutesAndHours) {
  EXPECT_EQ(tomodem::duration_text(12.4), "12 s");
  EXPECT_EQ(tomodem::duration_text(190), "3 min 10 s");
  EXPECT_EQ(tomodem::duration_text(3725), "1 h 02 min");
  EXPECT_EQ(tomodem::duration_text(-1), "?");
}

// CLI11 read integer options with strtoll/strtoull in base 0: `--size 010` was octal 8, `0x10` hex
// 16, 2^63 clamped to 2^63 - 1 and -1 wrapped to 2^64 - 1 in an unsigned option, all with exit 0.
// cli::parse now reads every integer option in decimal and refuses, naming the option and the
// value (exit 2), a number its type cannot hold, a negative unsigned one and other forms.
namespace {
struct IntegerOptions {
  int size = -1;
  long steps = -1;
  uint64_t count = 0;
  std::vector<int> list;
  std::string err;
  std::optional<int> parse(std::vector<std::string> words) {
    CLI::App app{"t", "t"};
    app.add_option("--size", size);
    app.add_option("--steps", steps);
    app.add_option("--count", count);
    app.add_option("--list", list)->delimiter(',');
    words.insert(words.begin(), "t");
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    testing::internal::CaptureStderr();
    const std::optional<int> code = tomodem::cli::parse(app, int(argv.size()), argv.data());
    err = testing::internal::GetCapturedStderr();
    return code;
  }
};
}  // namespace

TEST(IntegerOptions, AreReadInDecimal) {
  IntegerOptions o;
  ASSERT_FALSE(o.parse({"--size", "010", "--steps", "-007", "--count", "0009", "--list", "010,020"})) << o.err;
  EXPECT_EQ(o.size, 10);
  EXPECT_EQ(o.steps, -7);
  EXPECT_EQ(o.count, 9u);
  EXPECT_EQ(o.list, (std::vector<int>{10, 20}));
  ASSERT_FALSE(o.parse({"--size", "0", "--steps", "+12", "--count", "00"})) << o.err;
  EXPECT_EQ(o.size, 0);
  EXPECT_EQ(o.steps, 12);
  EXPECT_EQ(o.count, 0u);
  ASSERT_FALSE(o.parse({"--steps", "9223372036854775807", "--count", "18446744073709551615"})) << o.err;
  EXPECT_EQ(o.steps, 9223372036854775807L);
  EXPECT_EQ(o.count, 18446744073709551615ULL);
}

TEST(IntegerOptions, OverflowNegativeUnsignedAndOtherFormsAreRefused) {
  const std::vector<std::vector<std::string>> refused = {
      {"--steps", "9223372036854775808"},   // was clamped to 2^63 - 1
      {"--steps", "-99999999999999999999"}, // clamped to -2^63
      {"--count", "18446744073709551616"},  // clamped to 2^64 - 1
      {"--count", "-1"},                    // wrapped to 2^64 - 1
      {"--size", "0x10"},                   // hex 16
      {"--size", "1e3"},
      {"--size", "2.5"},
      {"--size", "99999999999"},            // beyond int: CLI11's own check, still naming the option
      {"--list", "1,0x10"}};
  for (const auto& args : refused) {
    IntegerOptions o;
    const std::optional<int> code = o.parse(args);
    ASSERT_TRUE(code) << args[0] << " " << args[1] << " was accepted";
    EXPECT_EQ(*code, tomodem::exit_code::bad_input) << args[1];
    EXPECT_NE(o.err.find(args[0]), std::string::npos) << o.err;
    EXPECT_NE(o.err.find(args[1].substr(args[1].find(',') + 1)), std::string::npos) << o.err;
  }
}
