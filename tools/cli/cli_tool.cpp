#include "cli_tool.hpp"

#include <charconv>
#include <exception>
#include <iostream>
#include <map>
#include <memory>
#include <string>

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
    std::cerr << where << ": " << e.what() << "\nrun '" << where << " --help' for the usage\n";
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
