#include "tripodal/core/diagnostic.hpp"

#include <catch2/catch.hpp>

using namespace tripodal;

TEST_CASE("diagnostics print gcc-style and count errors") {
  Diagnostics d;
  d.error({"net.xml", 12, 7}, "unknown element <plase>");
  d.warning({"net.xml", 3, 0}, "place P9 can never be marked");
  d.note({}, "while loading");
  CHECK(d.error_count() == 1);
  CHECK(d.has_errors());
  CHECK(d.all()[0].str() == "net.xml:12:7: error: unknown element <plase>");
  CHECK(d.all()[1].str() == "net.xml:3: warning: place P9 can never be marked");
  CHECK(d.all()[2].str() == "<input>: note: while loading");
}

TEST_CASE("ConfigError carries every diagnostic in what()") {
  Diagnostics d;
  d.error({"a.xml", 1, 1}, "first");
  d.error({"a.xml", 2, 1}, "second");
  const ConfigError e(d);
  CHECK(std::string(e.what()) == "a.xml:1:1: error: first\na.xml:2:1: error: second\n");
  CHECK(e.diagnostics().error_count() == 2);
}
