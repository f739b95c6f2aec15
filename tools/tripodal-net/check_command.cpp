// `tripodal-net check FILE...`: loads each net and reports every error and structural warning.
#include <algorithm>
#include <filesystem>
#include <ostream>

#include "command.hpp"
#include "net_tool_util.hpp"

namespace tripodal::net_tool {
namespace {

constexpr std::string_view kHelp =
    "usage: tripodal-net check [--no-warnings] FILE|DIR...\n\n"
    "Loads each configuration net (native XML or PNML, by extension then root element) and prints\n"
    "every problem gcc-style, FILE:LINE:COL: error|warning: MESSAGE, then one summary line per\n"
    "file. A directory stands for its *.xml and *.pnml files (not recursive).\n\n"
    "  --no-warnings  leave out the structural warnings (places never marked, transitions never\n"
    "                 enabled)\n\n"
    "exit codes: 0 every net is valid (warnings allowed), 1 a net has errors, 2 bad command line,\n"
    "            3 a file or directory could not be read\n";

enum class FileStatus { valid, invalid, unreadable };

// Checks one net file. Further checks (behavioural analysis) are added here as calls on the
// loaded net that append to `diagnostics`.
FileStatus check_file(const std::filesystem::path& file, const LoadOptions& options, std::ostream& out,
                      std::ostream& err) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    err << file.string() << ": error: cannot open file\n";
    return FileStatus::unreadable;
  }
  Diagnostics diagnostics;
  const auto net = load_net(file, diagnostics, options);
  err << diagnostics.str();
  if (!net) {
    out << file.string() << ": " << diagnostics.error_count() << " error(s)\n";
    return FileStatus::invalid;
  }
  std::size_t arcs = 0;
  for (const auto& t : net->transitions()) arcs += t.inputs.size() + t.outputs.size() + t.reads.size() + t.inhibitors.size();
  const std::size_t warnings = diagnostics.all().size();
  out << file.string() << ": ok (" << net->places().size() << " places, " << net->transitions().size()
      << " transitions, " << arcs << " arcs";
  if (warnings > 0) out << ", " << warnings << " warning(s)";
  out << ")\n";
  return FileStatus::valid;
}

int run_check(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  LoadOptions options;
  std::vector<std::filesystem::path> files;
  bool unreadable = false;
  for (const auto& a : args) {
    if (a == "--no-warnings") {
      options.structural_warnings = false;
    } else if (a.size() > 1 && a[0] == '-') {
      err << "tripodal-net check: unknown option " << a << "\n" << kHelp;
      return kUsage;
    } else if (std::filesystem::is_directory(a)) {
      std::vector<std::filesystem::path> found;
      std::error_code ec;
      for (const auto& entry : std::filesystem::directory_iterator(a, ec)) {
        const auto ext = entry.path().extension().string();
        if (entry.is_regular_file() && (ext == ".xml" || ext == ".pnml")) found.push_back(entry.path());
      }
      if (ec) {
        err << a << ": error: cannot read directory\n";
        unreadable = true;
      }
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else {
      files.emplace_back(a);
    }
  }
  if (files.empty() && !unreadable) {
    err << "tripodal-net check: no net files given\n" << kHelp;
    return kUsage;
  }
  bool invalid = false;
  for (const auto& f : files) {
    const FileStatus s = check_file(f, options, out, err);
    unreadable = unreadable || s == FileStatus::unreadable;
    invalid = invalid || s == FileStatus::invalid;
  }
  if (unreadable) return kIoError;
  return invalid ? kFindings : kOk;
}

}  // namespace

TRIPODAL_NET_COMMAND("check", "validate nets: every error and structural warning, located", kHelp, &run_check);

}  // namespace tripodal::net_tool
