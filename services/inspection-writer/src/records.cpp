#include "cell/inspection/records.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "cell/error/error.h"
#include "cell/records/entries.h"

namespace cell::inspection {

namespace fs = std::filesystem;

namespace {

void FsyncPath(const fs::path& p, int flags) {
  int fd = open(p.c_str(), flags);
  if (fd < 0) throw Error(Errc::kIo, "cannot open " + p.string());
  int rc = fsync(fd);
  close(fd);
  if (rc != 0) throw Error(Errc::kIo, "fsync failed on " + p.string());
}

bool Match(const char* p, const char* s) {
  if (!*p) return !*s;
  if (*p == '*') return Match(p + 1, s) || (*s && Match(p, s + 1));
  if (*s && (*p == '?' || *p == *s)) return Match(p + 1, s + 1);
  return false;
}

bool SafeName(const std::string& n) {
  return !n.empty() && n.size() <= 128 && n.find('/') == std::string::npos && n != "." && n != "..";
}

}  // namespace

void WriteDurable(const fs::path& path, const std::string& content) {
  fs::create_directories(path.parent_path());
  fs::path tmp = path;
  tmp += ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << content;
    out.flush();
    if (!out) throw Error(Errc::kIo, "cannot write " + tmp.string());
  }
  FsyncPath(tmp, O_RDONLY);
  fs::rename(tmp, path);
  FsyncPath(path.parent_path(), O_RDONLY | O_DIRECTORY);
}

Records::Records(fs::path dir) : dir_(std::move(dir)) {
  fs::create_directories(dir_);
}

std::string Records::StoreRun(const nlohmann::json& r) {
  for (const char* k : {"station", "dispatch_id", "pallet", "programs", "started", "finished", "machine_s"})
    if (!r.contains(k)) throw Error(Errc::kInvalidArgument, std::string("run record without '") + k + "'");
  std::string station = r["station"].get<std::string>();
  if (!SafeName(station)) throw Error(Errc::kInvalidArgument, "bad station name in run record");
  std::string name = "run-" + station + "-" + std::to_string(r["dispatch_id"].get<long>()) + ".json";
  WriteDurable(dir_ / name, r.dump(2) + "\n");
  return name;
}

std::string Records::StoreFile(const std::string& station, const std::string& name, const std::string& text) {
  if (!SafeName(station) || !SafeName(name)) throw Error(Errc::kInvalidArgument, "bad inspection file name");
  WriteDurable(dir_ / station / name, text);
  return station + "/" + name;
}

nlohmann::json Records::List(const std::string& pattern) const {
  nlohmann::json rows = nlohmann::json::array();
  List(pattern, "", [&](const cell::records::InspectionEntry& e) {
    rows.push_back(cell::records::InspectionRow(e));
    return true;
  });
  return rows;
}

void Records::List(const std::string& pattern, const std::string& after,
                   const std::function<bool(const cell::records::InspectionEntry&)>& visit) const {
  std::vector<std::string> names;
  for (auto& e : fs::recursive_directory_iterator(dir_)) {
    if (!e.is_regular_file() || e.path().extension() == ".tmp") continue;
    // Lexical: fs::relative canonicalizes both paths (syscalls per entry), 12x the cost of the whole scan.
    std::string rel = e.path().lexically_relative(dir_).string();
    if (rel > after && Match(pattern.c_str(), rel.c_str())) names.push_back(std::move(rel));
  }
  std::sort(names.begin(), names.end());
  for (const auto& name : names) {
    cell::records::InspectionEntry entry = cell::records::InspectionEntryOf(name);
    std::error_code ec;  // a file removed meanwhile is listed without its size
    const auto size = fs::file_size(dir_ / name, ec);
    if (!ec) entry.size = static_cast<std::int64_t>(size);
    if (!visit(entry)) return;
  }
}

std::optional<std::string> Records::Cat(const std::string& name) const {
  if (name.find("..") != std::string::npos) return std::nullopt;
  std::error_code ec;
  if (!fs::is_regular_file(dir_ / name, ec)) return std::nullopt;  // a station's folder is no record
  std::ifstream in(dir_ / name, std::ios::binary);
  if (!in) return std::nullopt;
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace cell::inspection
