// The command line's grammar: which flags each command takes (everything else given is a usage
// error), the parsing of argv into flag values and command words, and the help texts.
#ifndef SPORTSIM_CLIENT_COMMAND_FLAGS_H_
#define SPORTSIM_CLIENT_COMMAND_FLAGS_H_

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sportsim::cli {

/// One flag a command takes: its absl name (underscores) and, when the flag's own help text is
/// not what it means here (names shared by several commands), the meaning for this command.
struct FlagUse {
  std::string_view name;
  std::string_view help = {};
};

/// A command ("table", "shoot"), its arguments, what it does and the flags it takes.
struct CommandSpec {
  std::string_view command;
  std::string_view sub;    // empty for `info`, `health`
  std::string_view args;   // the positional arguments and required flags, for the synopsis
  std::string_view what;
  std::vector<FlagUse> flags;
  bool series = false;     // has a csv form
  bool stream = false;     // prints one line per snapshot (jsonl)
  /// Flags refused with a word of their own (the flag and why), for likely confusions.
  std::vector<std::pair<std::string_view, std::string_view>> refusals = {};
};

enum class HelpRequest { kNone, kHelp, kHelpFull };

/// Parses argv: flags (--name value, --name=value, dashes or underscores) set their absl flags,
/// the rest are the command words. Returns a usage message (an unknown flag, a value that does
/// not parse, a flag given twice, a missing value).
std::optional<std::string> ParseArgs(int argc, char** argv, std::vector<std::string>* positional,
                                     HelpRequest* help);

/// `round concede`'s words given (--stroke, --hole, --match), in order; outside `round concede`
/// these names are ordinary flags.
const std::vector<std::string>& WordFlags();

/// The command's spec; null when there is none (an unknown command or subcommand).
const CommandSpec* FindCommand(std::string_view command, std::string_view sub);

/// A usage message naming the first flag given that the command does not take; nullopt when
/// every flag given applies (global flags always do).
std::optional<std::string> CheckFlagsApply(const CommandSpec& spec);

/// `sportsim COMMAND [SUB] --help`: the synopsis and every flag with its meaning and default.
/// Nullopt for an unknown command.
std::optional<std::string> CommandHelp(std::string_view command, std::string_view sub);
/// `sportsim --helpfull`: the usage text and every flag.
std::string FullHelp(std::string_view usage);

/// "--ball-speed" for "ball_speed".
std::string Dashed(std::string_view name);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_COMMAND_FLAGS_H_
