#include "cli_tool.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>

#include "tripodal/core/registry.hpp"
#include "tripodal/version.hpp"

namespace tripodal::cli {

namespace {

std::vector<Command>& table() {
  static std::vector<Command> commands;
  return commands;
}

// Lower-case labels, so that help reads like the rest of the tools' output ("usage: ...").
std::shared_ptr<CLI::Formatter> formatter() {
  auto f = std::make_shared<CLI::Formatter>();
  f->label("Usage", "usage");
  f->label("OPTIONS", "OPTIONS");
  f->column_width(28);
  return f;
}

std::string with_newline(std::string_view text) {
  std::string s(text);
  if (!s.empty() && s.back() != '\n') s += '\n';
  return s;
}

}  // namespace

CLI::Validator positive_count() {
  return {[](std::string& text) {
            std::size_t v = 0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
            if (ec == std::errc() && end == text.data() + text.size() && v > 0) return std::string();
            return "expected a whole number > 0, got '" + text + "'";
          },
          "N>0"};
}

CLI::Validator whole_number(std::uint64_t max) {
  return {[max](std::string& text) {
            // CLI11 reads an unsigned option with strtoull, which takes "-1" as 2^64-1 and caps a
            // number beyond 2^64-1 at it: both are refused here, before that conversion.
            std::uint64_t v = 0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
            if (ec == std::errc() && end == text.data() + text.size() && v <= max) return std::string();
            return "expected a whole number from 0 to " + std::to_string(max) + ", got '" + text + "'";
          },
          "N"};
}

CLI::Validator positive_number() {
  return {[](std::string& text) {
            double v = 0.0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
            if (ec == std::errc() && end == text.data() + text.size() && v > 0.0 && v < 1e300) return std::string();
            return "expected a number > 0, got '" + text + "'";
          },
          "X>0"};
}

CLI::Validator non_negative_number() {
  return {[](std::string& text) {
            double v = 0.0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
            if (ec == std::errc() && end == text.data() + text.size() && v >= 0.0 && v < 1e300) return std::string();
            return "expected a number >= 0, got '" + text + "'";
          },
          "X>=0"};
}

namespace {

// The problem with writing into folder `dir` (which may not exist yet), or "" when it can be.
std::string folder_problem(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::path p = dir.empty() ? std::filesystem::path(".") : dir;
  if (std::filesystem::exists(p, ec)) {
    if (!std::filesystem::is_directory(p, ec)) return "'" + p.string() + "' is not a folder";
    if (::access(p.c_str(), W_OK | X_OK) != 0) return "the folder '" + p.string() + "' is not writable";
    return {};
  }
  // Created by the command: the nearest existing folder above must let it.
  std::filesystem::path up = std::filesystem::absolute(p, ec).parent_path();
  while (!up.empty() && !std::filesystem::exists(up, ec)) {
    if (up == up.parent_path()) break;
    up = up.parent_path();
  }
  if (!std::filesystem::is_directory(up, ec))
    return "'" + up.string() + "' is not a folder, so '" + p.string() + "' cannot be made";
  if (::access(up.c_str(), W_OK | X_OK) != 0) {
    return "'" + p.string() + "' cannot be made: the folder '" + up.string() + "' is not writable";
  }
  return {};
}

}  // namespace

CLI::Validator writable_folder() {
  return {[](std::string& text) { return folder_problem(text); }, "DIR"};
}

CLI::Validator writable_file() {
  return {[](std::string& text) {
            const std::filesystem::path p(text);
            std::error_code ec;
            if (std::filesystem::is_directory(p, ec)) return "'" + text + "' is a folder, expected a file";
            if (std::filesystem::exists(p, ec) && ::access(p.c_str(), W_OK) != 0)
              return "the file '" + text + "' is not writable";
            return folder_problem(p.parent_path());
          },
          "FILE"};
}

std::string did_you_mean(const CLI::App& app, int argc, const char* const* argv) {
  const CLI::App* at = &app;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;
    // "-1" is a value (a refused --seed -1), not an option.
    const bool negative_number =
        arg.size() > 1 && arg[0] == '-' && (std::isdigit(static_cast<unsigned char>(arg[1])) != 0 || arg[1] == '.');
    if (arg.size() > 1 && arg[0] == '-' && !negative_number) {
      const std::string name = arg.substr(0, arg.find('='));
      if (at->get_option_no_throw(name) != nullptr || name == "--help" || name == "-h" || name == "--version") continue;
      std::vector<std::string> known;
      for (const CLI::Option* o : at->get_options()) {
        for (const std::string& l : o->get_lnames()) known.push_back("--" + l);
      }
      const auto close = closest_name(name, known);
      return "unknown option '" + name + "'" + (close ? "; did you mean '" + *close + "'?" : std::string());
    }
    const std::vector<const CLI::App*> subs = at->get_subcommands([](const CLI::App*) { return true; });
    if (subs.empty()) continue;  // a positional argument or an option's value of a command
    const auto next = std::find_if(subs.begin(), subs.end(), [&](const CLI::App* s) { return s->check_name(arg); });
    if (next != subs.end()) {
      at = *next;
      continue;
    }
    std::vector<std::string> names;
    names.reserve(subs.size());
    for (const CLI::App* s : subs) names.push_back(s->get_name());
    const auto close = closest_name(arg, names);
    std::string known;
    for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
    return "unknown command '" + arg + "'" + (close ? "; did you mean '" + *close + "'?" : "; the commands: " + known);
  }
  return {};
}

std::optional<int> parse_command_line(CLI::App& app, std::string_view name, std::string_view exit_codes, int argc, char** argv) {
  app.name(std::string(name));
  app.formatter(formatter());
  app.footer(std::string(exit_codes));
  app.set_version_flag("--version", std::string(name) + " " + std::string(tripodal::version_string()));
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return kOk;
  } catch (const CLI::CallForVersion& e) {
    std::cout << e.what() << '\n';
    return kOk;
  } catch (const CLI::ParseError& e) {
    std::cerr << name << ": " << e.what() << '\n';
    if (const std::string hint = did_you_mean(app, argc, argv); !hint.empty()) std::cerr << name << ": " << hint << '\n';
    std::cerr << "run '" << name << " --help' for the usage\n";
    return kUsage;
  }
  return std::nullopt;
}

bool register_command(const Command& command) {
  table().push_back(command);
  return true;
}

int run_tool(const Tool& tool, int argc, char** argv) {
  CLI::App app(with_newline(tool.description), std::string(tool.name));
  app.formatter(formatter());
  app.footer(std::string(tool.exit_codes));
  app.set_version_flag("--version", std::string(tool.name) + " " + std::string(tripodal::version_string()));
  app.require_subcommand(1);
  std::map<std::string_view, CLI::App*> groups;
  for (const auto& [name, summary] : tool.groups) {
    CLI::App* g = app.add_subcommand(std::string(name), std::string(summary));
    g->formatter(formatter());
    g->require_subcommand(1);
    groups[name] = g;
  }
  std::vector<std::pair<CLI::App*, Action>> actions;
  for (const Command& c : table()) {
    CLI::App* parent = &app;
    if (!c.group.empty()) {
      auto it = groups.find(c.group);
      if (it == groups.end()) {
        // A command naming a group the tool does not list gets one without a summary.
        it = groups.emplace(c.group, app.add_subcommand(std::string(c.group))).first;
        it->second->require_subcommand(1);
      }
      parent = it->second;
    }
    CLI::App* sub = parent->add_subcommand(std::string(c.name), std::string(c.summary));
    sub->formatter(formatter());
    sub->footer(with_newline(c.description) + "\n" + std::string(c.exit_codes));
    actions.emplace_back(sub, c.setup(*sub));
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return kOk;
  } catch (const CLI::CallForAllHelp&) {
    std::cout << app.help("", CLI::AppFormatMode::All);
    return kOk;
  } catch (const CLI::CallForVersion& e) {
    std::cout << e.what() << '\n';
    return kOk;
  } catch (const CLI::ParseError& e) {
    // The error names the option or command; the help of the command being parsed follows.
    std::string where(tool.name);
    const CLI::App* at = &app;
    while (!at->get_subcommands().empty()) {
      at = at->get_subcommands().front();
      where += " " + at->get_name();
    }
    // A mistyped command is named with what it probably meant (CLI11 says "A subcommand is
    // required"); a mistyped option gets the suggestion after CLI11's message.
    const std::string hint = did_you_mean(app, argc, argv);
    if (hint.rfind("unknown command", 0) == 0) {
      std::cerr << where << ": " << hint << '\n';
    } else {
      std::cerr << where << ": " << e.what() << '\n';
      if (!hint.empty()) std::cerr << where << ": " << hint << '\n';
    }
    std::cerr << "run '" << where << " --help' for the usage\n";
    return kUsage;
  }

  for (const auto& [sub, action] : actions) {
    if (!sub->parsed()) continue;
    const std::string where = std::string(tool.name) + " " +
                              (sub->get_parent() != &app ? sub->get_parent()->get_name() + " " : std::string()) +
                              sub->get_name();
    try {
      return action(std::cout, std::cerr);
    } catch (const std::exception& e) {
      std::cerr << where << ": " << e.what() << '\n';
      return tool.exception_exit;
    }
  }
  return kUsage;  // unreachable: require_subcommand(1) on the tool and every group
}

}  // namespace tripodal::cli
