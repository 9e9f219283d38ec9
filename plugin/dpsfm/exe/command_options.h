// A command's options: registered with COLMAP's OptionManager, which parses
// them (and COLMAP's own: --project_path, logging), and kept here for
// `--help`. COLMAP's help is one flat list printed through glog (3.10 also
// prints defaults in full binary precision), so the commands print their
// own manual instead: what the command does, how to call it, then the
// options in groups, the common ones first, each with its default as
// written and what it does in words with its unit.
#pragma once

#include <iosfwd>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "colmap/controllers/option_manager.h"

namespace dpsfm {

class CommandOptions {
 public:
  // `usage`: lines of example calls; `summary`: what the command does.
  CommandOptions(std::string command,
                 std::string summary,
                 std::vector<std::string> usage);

  // Options added after this belong to the group `title`.
  void Group(const std::string& title);

  template <typename T>
  void AddRequired(const std::string& name, T* value, const std::string& help);
  template <typename T>
  void AddDefault(const std::string& name, T* value, const std::string& help);

  // -h or --help: prints the manual to `out`, sets *exit_code to 0 and
  // returns false. Otherwise parses with COLMAP's option manager; false
  // (and *exit_code 1) when that fails (it has printed why).
  bool Parse(int argc, char** argv, std::ostream& out, int* exit_code);

  std::string Manual() const;

 private:
  struct Entry {
    std::string group;
    std::string name;
    std::string value_name;  // PATH, N, X, 0|1, TEXT
    std::string default_text;
    std::string help;
    bool required = false;
  };

  template <typename T>
  static std::string DefaultText(const T& value);
  template <typename T>
  static std::string ValueName(const std::string& name);
  void Record(const std::string& name,
              std::string value_name,
              std::string default_text,
              const std::string& help,
              bool required);

  std::string program_ = "colmap";
  std::string command_;
  std::string summary_;
  std::vector<std::string> usage_;
  std::string group_;
  std::vector<Entry> entries_;
  colmap::OptionManager manager_;
};

template <typename T>
std::string CommandOptions::DefaultText(const T& value) {
  std::ostringstream text;
  if constexpr (std::is_same<T, bool>::value) {
    text << (value ? 1 : 0);
  } else {
    text << value;  // doubles with 6 significant digits: 0.1, not 0.1000..1
  }
  return text.str();
}

template <typename T>
std::string CommandOptions::ValueName(const std::string& name) {
  if constexpr (std::is_same<T, bool>::value) {
    return "0|1";
  } else if constexpr (std::is_integral<T>::value) {
    return "N";
  } else if constexpr (std::is_floating_point<T>::value) {
    return "X";
  } else {
    const std::string suffix = "_path";
    return name.size() > suffix.size() &&
                   name.compare(
                       name.size() - suffix.size(), suffix.size(), suffix) == 0
               ? "PATH"
               : "TEXT";
  }
}

template <typename T>
void CommandOptions::AddRequired(const std::string& name,
                                 T* value,
                                 const std::string& help) {
  manager_.AddRequiredOption(name, value, help);
  Record(name, ValueName<T>(name), "", help, /*required=*/true);
}

template <typename T>
void CommandOptions::AddDefault(const std::string& name,
                                T* value,
                                const std::string& help) {
  manager_.AddDefaultOption(name, value, help);
  Record(name, ValueName<T>(name), DefaultText(*value), help, false);
}

}  // namespace dpsfm
