// Running the openssl command (private to cell_security).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace cell::security::detail {

// The program openssl names: itself when it contains a '/', else the first executable of that name in
// PATH. Throws cell::Error(kFailedPrecondition) naming it when there is none.
std::filesystem::path FindProgram(const std::string& program);

// Runs `program args...` (fork and exec, no shell) with stdin /dev/null, stdout discarded and umask 077, so
// every file it creates is the owner's only. Throws cell::Error(kInternal) when it does not exit 0, with
// the subcommand and the last line it wrote to stderr.
void RunOpenssl(const std::filesystem::path& program, const std::vector<std::string>& args);

}  // namespace cell::security::detail
