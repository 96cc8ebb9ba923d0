// The one table of dialects.
#include "cell/interp/interp.h"

#include <algorithm>
#include <cctype>

#include "cell/error/error.h"
#include "cell/interp/balt.h"
#include "cell/interp/emco.h"
#include "cell/interp/ktapl.h"
#include "cell/interp/okuma.h"

namespace cell::interp {
namespace {

bool SameCi(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::toupper(static_cast<unsigned char>(x)) == std::toupper(static_cast<unsigned char>(y));
         });
}

}  // namespace

const std::vector<const Dialect*>& Dialects() {
  static const std::vector<const Dialect*> kTable = {
      &KtaplDialect(),
      &OkumaDialect(),
      &EmcoDialect(),
      &BaltDialect(),
  };
  return kTable;
}

const Dialect* FindDialect(std::string_view name) {
  for (const Dialect* d : Dialects()) {
    if (SameCi(d->name(), name)) return d;
    for (std::string_view alias : d->aliases()) {
      if (SameCi(alias, name)) return d;
    }
  }
  return nullptr;
}

std::string DialectList() {
  std::string out;
  const auto& all = Dialects();
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i > 0) out += i + 1 == all.size() ? " or " : ", ";
    out += all[i]->name();
  }
  return out;
}

std::string DialectChoices() {
  std::string out;
  for (const Dialect* d : Dialects()) {
    if (!out.empty()) out += '|';
    out += d->name();
  }
  return out;
}

const Dialect& DialectOrThrow(std::string_view name) {
  const Dialect* d = FindDialect(name);
  if (d == nullptr) {
    throw Error(Errc::kInvalidArgument,
                "unknown dialect '" + std::string(name.substr(0, 32)) + "' (use " + DialectList() + ")");
  }
  return *d;
}

std::unique_ptr<Run> StartRun(const RunOptions& options) {
  return DialectOrThrow(options.dialect).StartRun(options);
}

}  // namespace cell::interp
