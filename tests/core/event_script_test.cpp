#include "tripodal/core/event_script.hpp"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

using namespace tripodal;

TEST_CASE("event scripts: events, fact changes, comments and blank lines") {
  const EventScript s = parse_event_script(
      "# PrCleaning: a temporary loss\n"
      "\n"
      "0.5 localizer.lost\n"
      "  3   set battery_low true   # low now\n"
      "3.0 set room \"kitchen 2\"\n"
      "3.0 localizer.ok\n"
      "1e1 BhCleaning.done\n",
      "loss.script");
  REQUIRE(s.entries.size() == 5);
  CHECK(s.source == "loss.script");
  CHECK(s.entries[0].kind == ScriptEntry::Kind::event);
  CHECK(s.entries[0].time == time_from_seconds(0.5));
  CHECK(s.entries[0].name == "localizer.lost");
  CHECK(s.entries[0].where.str() == "loss.script:3:1");
  CHECK(s.entries[1].kind == ScriptEntry::Kind::set_fact);
  CHECK(s.entries[1].name == "battery_low");
  CHECK(s.entries[1].value_text == "true");
  CHECK_FALSE(s.entries[1].value_quoted);
  CHECK(s.entries[1].value_where.str() == "loss.script:4:23");
  CHECK(s.entries[2].value_text == "kitchen 2");
  CHECK(s.entries[2].value_quoted);
  CHECK(s.entries[3].time == time_from_seconds(3.0));
  CHECK(s.entries[4].time == time_from_seconds(10.0));
  CHECK(parse_event_script("").entries.empty());
  CHECK(parse_event_script("# only a comment").entries.empty());
}

TEST_CASE("event scripts: errors name line and column, all at once") {
  CHECK_THROWS_WITH(parse_event_script("abc localizer.lost\n", "s"),
                    Catch::Contains("s:1:1: error: expected a time in seconds") && Catch::Contains("'abc'"));
  CHECK_THROWS_WITH(parse_event_script("1.0 a\n0.5 b\n", "s"),
                    Catch::Contains("s:2:1") && Catch::Contains("earlier than 1 on line 1"));
  CHECK_THROWS_WITH(parse_event_script("-1 a\n", "s"), Catch::Contains("s:1:1") && Catch::Contains("negative"));
  CHECK_THROWS_WITH(parse_event_script("1.0\n", "s"), Catch::Contains("s:1:4") && Catch::Contains("expected an event"));
  CHECK_THROWS_WITH(parse_event_script("1.0 set\n", "s"), Catch::Contains("s:1:8: error: expected a fact name"));
  CHECK_THROWS_WITH(parse_event_script("1.0 set flag\n", "s"),
                    Catch::Contains("s:1:13") && Catch::Contains("expected a value after the fact name 'flag'"));
  CHECK_THROWS_WITH(parse_event_script("1.0 set flag true extra\n", "s"),
                    Catch::Contains("s:1:19") && Catch::Contains("unexpected 'extra'"));
  CHECK_THROWS_WITH(parse_event_script("1.0 localizer.lost now\n", "s"), Catch::Contains("s:1:20"));
  CHECK_THROWS_WITH(parse_event_script("1.0 set room \"kitchen\n", "s"),
                    Catch::Contains("s:1:14") && Catch::Contains("unterminated string"));
  CHECK_THROWS_WITH(parse_event_script("1.0 bad!name\n", "s"),
                    Catch::Contains("s:1:8") && Catch::Contains("invalid character '!'"));
  CHECK_THROWS_WITH(parse_event_script("nan x\n", "s"), Catch::Contains("s:1:1"));
  try {
    (void)parse_event_script("x a\n1 ok\n2\n0 late\n", "s");
    FAIL("expected ConfigError");
  } catch (const ConfigError& e) {
    REQUIRE(e.diagnostics().error_count() == 3);
    CHECK(e.diagnostics().all()[0].where.line == 1);
    CHECK(e.diagnostics().all()[1].where.line == 3);
    CHECK(e.diagnostics().all()[2].where.line == 4);
  }
}

TEST_CASE("event scripts load from files, a missing file is an error naming it") {
  const auto dir = std::filesystem::temp_directory_path() / "tripodal_event_script_test";
  std::filesystem::create_directories(dir);
  const auto file = dir / "run.script";
  {
    std::ofstream out(file);
    out << "0 go\n2.5 stop\n";
  }
  const EventScript s = load_event_script(file);
  REQUIRE(s.entries.size() == 2);
  CHECK(s.entries[1].where.file == file.string());
  CHECK_THROWS_WITH(load_event_script(dir / "missing.script"),
                    Catch::Contains("missing.script") && Catch::Contains("cannot read"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("event scripts: a time beyond the range of a Time saturates instead of overflowing") {
  // Found by fuzz_event_script: 8.9e58 s was converted to 64-bit nanoseconds, undefined behaviour.
  const EventScript s = parse_event_script(std::string(59, '8') + " cr\n\n", "fuzz.events");
  REQUIRE(s.entries.size() == 1);
  CHECK(s.entries[0].time == time_from_seconds(kMaxSeconds));
}
