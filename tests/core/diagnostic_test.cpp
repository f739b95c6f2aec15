#include "tripodal/core/diagnostic.hpp"

#include <catch2/catch.hpp>
#include <string>
#include <thread>
#include <vector>

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

TEST_CASE("SourceFile: one interned copy per name, safe to create from several threads", "[threads]") {
  const SourceFile none;
  CHECK(none.empty());
  CHECK(none.str().empty());
  CHECK(SourceFile("").empty());
  CHECK(SourceLocation{}.str() == "<input>");

  const std::string long_path = "/home/robot/configs/petri/a_rather_long_file_name_for_a_net.xml";
  const SourceFile a(long_path);
  const SourceFile b{std::string_view(long_path)};
  CHECK(&a.str() == &b.str());  // interned: one copy
  CHECK(a == long_path);
  CHECK_FALSE(a == "other.xml");
  const SourceLocation where{long_path, 12, 5};
  CHECK(where.str() == long_path + ":12:5");
  const SourceLocation copy = where;  // a copy shares the name
  CHECK(&copy.file.str() == &a.str());

  // Threads interning the same names get the same copies, and distinct names stay distinct.
  std::vector<std::vector<const std::string*>> seen(4);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < seen.size(); ++t) {
    threads.emplace_back([&seen, t] {
      for (int i = 0; i < 500; ++i) seen[t].push_back(&SourceFile("thread_test_" + std::to_string(i) + ".xml").str());
    });
  }
  for (std::thread& th : threads) th.join();
  for (std::size_t t = 1; t < seen.size(); ++t) CHECK(seen[t] == seen[0]);
  CHECK(*seen[0][7] == "thread_test_7.xml");
  CHECK(seen[0][7] != seen[0][8]);
}
