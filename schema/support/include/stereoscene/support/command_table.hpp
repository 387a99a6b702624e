#pragma once

/// One command table per tool: each row registers a subcommand with its flags and runs it once
/// parsed, so the list of commands is written once and drives the help, the dispatch and the
/// default command. Header-only: only the executables, which link CLI11, include it.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace stereoscene::support {

/// One subcommand: registered on the app, run when parsed.
struct Command {
    CLI::App* sub = nullptr;   ///< the subcommand CLI11 parses
    std::function<int()> run;  ///< runs it with the parsed flags; returns the exit code
};

/// A row whose flags fill an Args that the row owns: add(app, args) registers the subcommand
/// and binds the flags, run(args, sub) runs it once parsed.
template <class Args, class Add, class Run>
Command make_command(CLI::App& app, Add&& add, Run run) {
    auto args = std::make_shared<Args>();
    CLI::App* sub = add(app, *args);
    return {sub, [args, sub, run]() { return run(*args, *sub); }};
}

/// The row of the table that was parsed, or nullptr.
inline const Command* parsed_command(const std::vector<Command>& table) {
    for (const auto& c : table)
        if (c.sub->parsed()) return &c;
    return nullptr;
}

/// True when `name` names a row.
inline bool is_command(const std::vector<Command>& table, const std::string& name) {
    for (const auto& c : table)
        if (c.sub->get_name() == name) return true;
    return false;
}

/// The rows' names, "a, b, c".
inline std::string command_names(const std::vector<Command>& table) {
    std::string names;
    for (const auto& c : table) names += (names.empty() ? "" : ", ") + c.sub->get_name();
    return names;
}

}  // namespace stereoscene::support
