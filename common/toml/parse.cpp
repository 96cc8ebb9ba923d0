#include "cell/toml/parse.h"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "cell/error/error.h"

namespace cell::tomlfile {

toml::table Parse(std::string_view text, const std::string& source) {
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw Error(Errc::kInvalidArgument, fmt::format("{}:{}:{}: {}", source, e.source().begin.line,
                                                    e.source().begin.column, e.description()));
  }
}

toml::table ParseFile(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(Errc::kIo, fmt::format("{}: cannot open: {}", file.string(), std::strerror(errno)));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(Errc::kIo, fmt::format("{}: read error", file.string()));
  return Parse(text.str(), file.string());
}

}  // namespace cell::tomlfile
