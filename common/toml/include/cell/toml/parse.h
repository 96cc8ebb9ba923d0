// TOML text to a table with the cell's error convention: a syntax error is cell::Error(kInvalidArgument)
// "SOURCE:LINE:COL: description", an unreadable file cell::Error(kIo) "FILE: reason".
#pragma once

#include <toml++/toml.h>
#include <filesystem>
#include <string>
#include <string_view>

namespace cell::tomlfile {

// `source` names the text in errors (a file name, a program store name).
toml::table Parse(std::string_view text, const std::string& source);
toml::table ParseFile(const std::filesystem::path& file);

}  // namespace cell::tomlfile
