#include "cell/scheduler/program_source.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "cell/error/error.h"
#include "cell/interp/ktapl_meta.h"
#include "cell/tooltable/tooltable.h"

namespace cell::scheduler {

ProgramMeta KtaplProgramMeta(std::string_view text, std::string_view name) {
  interp::KtaplMetadata heading = interp::ExtractKtaplMetadata(text, {.whole_seconds = true});
  for (const interp::KtaplMetaWarning& w : heading.warnings) {
    if (w.kind == interp::KtaplMetaWarning::Kind::kValue && (w.mnemonic == "UTL" || w.mnemonic == "UCY")) {
      throw Error(Errc::kInvalidArgument, fmt::format("{}:{}:{}: error: {}", name, w.line, w.column, w.text));
    }
  }
  ProgramMeta meta;
  meta.name = std::string(name);
  for (const std::string& written : heading.tools) {
    std::string tool = tooltable::NormalizeToolNumber(written);  // "0034" -> "34"
    if (std::find(meta.tools.begin(), meta.tools.end(), tool) == meta.tools.end()) {
      meta.tools.push_back(std::move(tool));
    }
  }
  if (heading.cycle_s) meta.ucy_s = static_cast<std::int64_t>(*heading.cycle_s);
  return meta;
}

std::optional<ProgramMeta> TextProgramSource::Lookup(std::string_view name) {
  std::optional<std::string> text = fetch_(name);
  if (!text) return std::nullopt;
  return KtaplProgramMeta(*text, name);
}

std::optional<ProgramMeta> MemoryProgramSource::Lookup(std::string_view name) {
  auto it = texts_.find(name);
  if (it == texts_.end()) return std::nullopt;
  return KtaplProgramMeta(it->second, name);
}

}  // namespace cell::scheduler
