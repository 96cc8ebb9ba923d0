#include "cell/scheduler/program_source.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "cell/error/error.h"
#include "cell/interp/interp.h"
#include "cell/tooltable/tooltable.h"

namespace cell::scheduler {

ProgramMeta ReadProgramMeta(std::string_view text, std::string_view dialect, std::string_view name) {
  const interp::Dialect* d = interp::FindDialect(dialect);
  if (d == nullptr) {
    throw Error(Errc::kInvalidArgument, fmt::format("program {} has {} (the store records one of {})", name,
                                                    dialect.empty() ? std::string("no dialect")
                                                                    : fmt::format("dialect '{}'", dialect),
                                                    interp::DialectList()));
  }
  interp::Heading heading = d->ReadHeading(text, {.whole_seconds = true});
  for (const interp::HeadingNotice& w : heading.notices) {
    if (w.kind == interp::HeadingNotice::Kind::kValue && (w.key == "UTL" || w.key == "UCY")) {
      throw Error(Errc::kInvalidArgument, fmt::format("{}:{}:{}: error: {}", name, w.line, w.column, w.text));
    }
  }
  ProgramMeta meta;
  meta.name = std::string(name);
  meta.dialect = std::string(d->name());
  for (const std::string& written : heading.tools) {
    std::string tool = tooltable::NormalizeToolNumber(written);  // "0034" -> "34"
    if (std::find(meta.tools.begin(), meta.tools.end(), tool) == meta.tools.end()) {
      meta.tools.push_back(std::move(tool));
    }
  }
  if (heading.cycle_s) meta.ucy_s = static_cast<std::int64_t>(*heading.cycle_s);
  return meta;
}

namespace {

// FNV-1a, 64 bits: stable across processes and builds (a stored key), and enough to tell revisions apart.
std::string Fingerprint(const StoredProgram& p) {
  std::uint64_t h = 14695981039346656037ull;
  auto add = [&h](std::string_view s) {
    for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  };
  add(p.dialect);
  add("\n");
  add(p.text);
  return fmt::format("{:016x}", h);
}

ProgramMeta MetaOf(const StoredProgram& p, std::string_view name) {
  if (p.type == "part_model") {
    ProgramMeta meta;
    meta.name = std::string(name);
    meta.part_model = true;
    return meta;
  }
  ProgramMeta meta = ReadProgramMeta(p.text, p.dialect, name);
  meta.revision = Fingerprint(p);
  return meta;
}

}  // namespace

std::optional<ProgramMeta> TextProgramSource::Lookup(std::string_view name) {
  std::optional<StoredProgram> p = fetch_(name);
  if (!p) return std::nullopt;
  return MetaOf(*p, name);
}

std::optional<ProgramMeta> MemoryProgramSource::Lookup(std::string_view name) {
  auto it = texts_.find(name);
  if (it == texts_.end()) return std::nullopt;
  return MetaOf(it->second, name);
}

}  // namespace cell::scheduler
