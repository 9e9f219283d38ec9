#include "dpsfm/exe/command_options.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <ostream>

#include <glog/logging.h>

#include "dpsfm/colmap/util/colmap_compat.h"

namespace dpsfm {
namespace {

// `text` wrapped at `width` columns, each line indented by `indent`.
std::string Wrap(const std::string& text, int indent, int width) {
  std::istringstream words(text);
  std::string word, line, wrapped;
  const std::string pad(indent, ' ');
  while (words >> word) {
    if (!line.empty() &&
        static_cast<int>(pad.size() + line.size() + 1 + word.size()) > width) {
      wrapped += pad + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) wrapped += pad + line + "\n";
  return wrapped;
}

}  // namespace

CommandOptions::CommandOptions(std::string command,
                               std::string summary,
                               std::vector<std::string> usage)
    : command_(std::move(command)),
      summary_(std::move(summary)),
      usage_(std::move(usage)) {}

void CommandOptions::Group(const std::string& title) { group_ = title; }

void CommandOptions::Record(const std::string& name,
                            std::string value_name,
                            std::string default_text,
                            const std::string& help,
                            bool required) {
  Entry entry;
  entry.group = group_;
  entry.name = name;
  entry.value_name = std::move(value_name);
  entry.default_text = std::move(default_text);
  entry.help = help;
  entry.required = required;
  entries_.push_back(std::move(entry));
}

std::string CommandOptions::Manual() const {
  constexpr int kWidth = 79;
  std::ostringstream text;
  text << program_ << " " << command_ << "\n\n"
       << Wrap(summary_, 2, kWidth) << "\n";
  text << "Usage:\n";
  for (const std::string& line : usage_) {
    text << "  " << program_ << " " << command_ << " " << line << "\n";
  }
  std::string group = "\x01";  // no group yet
  for (const Entry& entry : entries_) {
    if (entry.group != group) {
      group = entry.group;
      text << "\n" << group << ":\n";
    }
    text << "  --" << entry.name << " " << entry.value_name;
    if (entry.required) {
      text << "  (required)";
    } else if (!entry.default_text.empty()) {
      text << "  (default " << entry.default_text << ")";
    }
    text << "\n" << Wrap(entry.help, 6, kWidth);
  }
  text << "\nCOLMAP's own options work as in every colmap command: "
          "--project_path FILE.ini\n(the options above, one per line as "
          "name=value) and --log_level N.\n";
  return text.str();
}

bool CommandOptions::Parse(int argc,
                           char** argv,
                           std::ostream& out,
                           int* exit_code) {
  // `colmap` (the checkout route) or `dpsfm` (the installed route), as the
  // user called it.
  if (argc > 0 && argv[0] != nullptr) {
    const std::string program = std::filesystem::path(argv[0]).filename();
    if (!program.empty()) program_ = program;
  }
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "-h") == 0 ||
        std::strcmp(argv[i], "--help") == 0) {
      out << Manual();
      *exit_code = EXIT_SUCCESS;
      return false;
    }
  }
  if (!ParseOptions(&manager_, argc, argv)) {
    *exit_code = EXIT_FAILURE;
    return false;
  }
  // glog colours by the TERM variable alone, so a log redirected to a file
  // from a colour terminal would carry escape codes: colour only a
  // terminal.
  if (!isatty(fileno(stderr))) FLAGS_colorlogtostderr = false;
  return true;
}

}  // namespace dpsfm
