// Parser robustness: thousands of seeded mutations (truncations, byte flips, deletions,
// insertions of XML metacharacters, duplicated chunks) of valid native and PNML files. The
// loaders must never crash or throw, and every failed load must report at least one error, each
// located at FILE:LINE:COL inside the text. Runs under ASan/UBSan in CI.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "tripodal/core/net_loader.hpp"

using namespace tripodal;

namespace {

std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string mutate(std::string text, std::mt19937& rng) {
  const auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n == 0 ? 0 : n - 1)(rng); };
  static constexpr char kMeta[] = {'<', '>', '"', '\'', '&', '/', '=', ';', '!', '?', '-', '\n', '\0', ' ', 'x', '#'};
  const int edits = std::uniform_int_distribution<int>(1, 4)(rng);
  for (int k = 0; k < edits && !text.empty(); ++k) {
    switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
      case 0:  // truncate
        text.resize(pick(text.size()));
        break;
      case 1:  // flip a byte to anything
        text[pick(text.size())] = static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
        break;
      case 2: {  // delete a range
        const auto at = pick(text.size());
        text.erase(at, std::min<std::size_t>(pick(40) + 1, text.size() - at));
        break;
      }
      case 3:  // insert a metacharacter
        text.insert(text.begin() + static_cast<std::ptrdiff_t>(pick(text.size() + 1)), kMeta[pick(sizeof kMeta)]);
        break;
      case 4: {  // duplicate a chunk elsewhere
        const auto from = pick(text.size());
        const std::string chunk = text.substr(from, pick(80) + 1);
        text.insert(pick(text.size() + 1), chunk);
        break;
      }
      default: {  // change a digit (counts, weights, delays)
        const auto at = pick(text.size());
        const auto digit = std::find_if(text.begin() + static_cast<std::ptrdiff_t>(at), text.end(),
                                        [](char c) { return c >= '0' && c <= '9'; });
        if (digit != text.end()) *digit = "0-9x"[pick(4)];
        break;
      }
    }
  }
  return text;
}

}  // namespace

TEST_CASE("loaders survive thousands of mutated files and locate every error") {
  const std::filesystem::path src = TRIPODAL_SOURCE_DIR;
  struct Seed {
    std::string name;
    std::string text;
  };
  std::vector<Seed> seeds = {
      {"PrCleaning.xml", read_file(src / "configs/petri/PrCleaning.xml")},
      {"example.xml", read_file(src / "docs/examples/net-format-example.xml")},
      {"Kanban2.pnml", read_file(src / "tests/data/pnml/Kanban2-test001.pnml")},
      {"pnp-interrupt.pnml", read_file(src / "tests/data/pnml/pnp-interrupt.pnml")},
  };
  {
    Diagnostics d;
    const auto net = load_net_from_string(seeds[0].text, "PrCleaning.xml", d);
    REQUIRE(net);
    seeds.push_back({"PrCleaning.pnml", net_to_string(*net, NetFormat::pnml)});
  }
  std::mt19937 rng(20260522);
  std::size_t failed_loads = 0;
  std::size_t loaded = 0;
  std::size_t bad_location = 0;
  for (const auto& seed : seeds) {
    REQUIRE(!seed.text.empty());
    const auto lines = static_cast<int>(std::count(seed.text.begin(), seed.text.end(), '\n')) + 200;
    for (int i = 0; i < 2000; ++i) {
      const std::string text = mutate(seed.text, rng);
      Diagnostics d;
      std::optional<PetriNet> net;
      REQUIRE_NOTHROW(net = load_net_from_string(text, seed.name, d));
      if (net) {
        ++loaded;
        CHECK_FALSE(d.has_errors());
        // What loads can be written and read back.
        const std::string again = net_to_string(*net, NetFormat::native_xml);
        Diagnostics d2;
        CHECK(load_net_from_string(again, "again.xml", d2));
        continue;
      }
      ++failed_loads;
      REQUIRE(d.has_errors());
      for (const auto& diag : d.all()) {
        const bool located = diag.where.file == seed.name && diag.where.line >= 1 && diag.where.line <= lines &&
                             diag.where.column >= 1 && !diag.message.empty();
        if (!located) {
          ++bad_location;
          UNSCOPED_INFO(diag.str());
        }
      }
    }
  }
  CHECK(bad_location == 0);
  // The mutations must exercise both paths (many rejected, some still valid).
  CHECK(failed_loads > 5000);
  CHECK(loaded > 100);
}
