#include "cell/config/dds.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "cell/config/config.h"
#include "cell/error/error.h"

namespace fs = std::filesystem;

namespace cell::config {
namespace {

std::string Env(const std::string& name) {
  const char* v = std::getenv(name.c_str());
  return v == nullptr ? std::string() : std::string(v);
}

bool IsEnvName(std::string_view n) {
  if (n.empty() || (n[0] >= '0' && n[0] <= '9')) return false;
  return std::all_of(n.begin(), n.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

// Expands text[i..] up to the '}' that closes the reference opened before i (depth counts nested ${...}).
std::string ExpandFrom(std::string_view text, size_t& i, std::string_view what, bool nested, int depth) {
  if (depth > 8) throw Error(Errc::kInvalidArgument, fmt::format("{}: ${{...}} nested too deeply", what));
  std::string out;
  while (i < text.size()) {
    char c = text[i];
    if (nested && c == '}') return out;  // the caller consumes it
    if (c != '$') {
      out += c;
      ++i;
      continue;
    }
    if (i + 1 < text.size() && text[i + 1] == '$') {
      out += '$';
      i += 2;
      continue;
    }
    if (i + 1 >= text.size() || text[i + 1] != '{') {
      out += c;
      ++i;
      continue;
    }
    size_t start = i;
    i += 2;
    size_t name_end = i;
    while (name_end < text.size() && text[name_end] != '}' && text[name_end] != ':') ++name_end;
    std::string name(text.substr(i, name_end - i));
    if (name_end >= text.size())
      throw Error(Errc::kInvalidArgument,
                  fmt::format("{}: '{}' is not closed with '}}'", what, text.substr(start, 24)));
    if (!IsEnvName(name))
      throw Error(Errc::kInvalidArgument, fmt::format("{}: '${{{}' is not a variable name", what, name));
    std::optional<std::string> dflt;
    i = name_end;
    if (text[i] == ':') {
      if (i + 1 >= text.size() || text[i + 1] != '-')
        throw Error(Errc::kInvalidArgument,
                    fmt::format("{}: ${{{}:...}}: only ${{NAME:-default}} is understood", what, name));
      i += 2;
      dflt = ExpandFrom(text, i, what, true, depth + 1);
      if (i >= text.size())
        throw Error(Errc::kInvalidArgument,
                    fmt::format("{}: ${{{}:-...}} is not closed with '}}'", what, name));
    }
    ++i;  // the closing '}'
    std::string value = Env(name);
    // The profiles size their peer ranges with it; unset, it is what the loopback profile would use.
    if (value.empty() && name == "CELL_DDS_PARTICIPANTS") value = std::to_string(DdsParticipants());
    if (!value.empty()) {
      out += value;
    } else if (dflt) {
      out += *dflt;
    } else {
      throw Error(Errc::kInvalidArgument,
                  fmt::format("{}: ${{{}}} is used but {} is not set in the environment", what, name, name));
    }
  }
  return out;  // nested: unterminated, the caller reports it
}

}  // namespace

bool IsDdsVendor(std::string_view v) {
  return std::find(std::begin(kDdsVendors), std::end(kDdsVendors), v) != std::end(kDdsVendors);
}

std::string DdsVendorList() {
  std::string out;
  for (auto v : kDdsVendors) out += (out.empty() ? "" : ", ") + std::string(v);
  return out;
}

DdsChoice DdsVendor(std::string_view station_setting) {
  std::string env = Env("CELL_DDS");
  if (!env.empty() && !IsDdsVendor(env))  // checked even when a station file decides: typos must not pass
    throw Error(Errc::kInvalidArgument, fmt::format("CELL_DDS={}: expected one of {}", env, DdsVendorList()));
  if (!station_setting.empty()) {
    if (!IsDdsVendor(station_setting))
      throw Error(Errc::kInvalidArgument,
                  fmt::format("station dds = '{}': expected one of {}", station_setting, DdsVendorList()));
    return {std::string(station_setting), "the station file"};
  }
  if (!env.empty()) return {env, "CELL_DDS"};
  return {std::string(kDdsVendors[0]), "the default"};
}

fs::path DdsProfile(std::string_view vendor) {
  std::string v = Env("CELL_DDS_PROFILE");
  if (v.empty()) return {};
  fs::path file;
  if (v.find('/') != std::string::npos) {
    file = v;
  } else {
    bool ok = v.size() <= 64 && std::all_of(v.begin(), v.end(), [](char c) {
                return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                       c == '_' || c == '-';
              });
    if (!ok)
      throw Error(Errc::kInvalidArgument,
                  fmt::format("CELL_DDS_PROFILE={}: a profile name is 1-64 letters, digits, '_' or '-' (or "
                              "give a path with a '/')",
                              v));
    file = ConfigDir() / "dds" / fmt::format("{}.{}.xml", v, vendor);
  }
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw Error(Errc::kNotFound,
                fmt::format("CELL_DDS_PROFILE={}: no {} profile {}", v, vendor, file.string()));
  return file;
}

std::string ExpandEnvironment(std::string_view text, std::string_view what) {
  size_t i = 0;
  return ExpandFrom(text, i, what, false, 0);
}

std::string LoadDdsProfile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(Errc::kIo, fmt::format("cannot read DDS profile {}", file.string()));
  std::stringstream ss;
  ss << in.rdbuf();
  return ExpandEnvironment(ss.str(), file.string());
}

int DdsParticipants() {
  const std::string set = Env("CELL_DDS_PARTICIPANTS");
  if (!set.empty()) {
    const bool digits = set.size() <= 4 && set.find_first_not_of("0123456789") == std::string::npos;
    const int n = digits ? std::stoi(set) : 0;
    if (n < 8 || n > kMaxDdsParticipants)
      throw Error(Errc::kInvalidArgument,
                  fmt::format("CELL_DDS_PARTICIPANTS '{}': expected a number from 8 to {}", set,
                              kMaxDdsParticipants));
    return n;
  }
  size_t stations = 0;
  try {
    stations = ListStations().size();
  } catch (const Error&) {  // no station directory: a tool or test outside a cell
  }
  constexpr int kMax = kMaxDdsParticipants - kClientSlots;
  const int wanted = static_cast<int>(std::min<size_t>(2 * stations + 16, kMax));
  return std::min(kMax, std::max(32, (wanted + 7) / 8 * 8));
}

}  // namespace cell::config
