// Durable run records and inspection files: one file each under a directory, written so that a
// crash leaves either the previous content or the new one, never a torn file.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cell/records/entries.h"

namespace cell::inspection {

// Writes `content` to `path` atomically and durably (temp file, fsync, rename, fsync directory).
void WriteDurable(const std::filesystem::path& path, const std::string& content);

class Records {
 public:
  explicit Records(std::filesystem::path dir);
  // A run record: stored as run-<station>-<dispatch>.json. Storing it again is harmless.
  std::string StoreRun(const nlohmann::json& record);
  // An inspection file of a station (KT text, CSV or QIF): <station>/<name>.
  std::string StoreFile(const std::string& station, const std::string& name, const std::string& text);
  // [{name, station, kind, size}] for names matching the pattern (* and ?).
  nlohmann::json List(const std::string& pattern) const;
  // `inspect ls --after NAME`: the entries of those names that sort after `after` (exclusive, byte order; ""
  // from the first), by name, one at a time until visit returns false. Only a visited entry's size is read.
  void List(const std::string& pattern, const std::string& after,
            const std::function<bool(const records::InspectionEntry&)>& visit) const;
  std::optional<std::string> Cat(const std::string& name) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace cell::inspection
