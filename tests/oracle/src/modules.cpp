// The registry of dialect modules, in the order the differential runs them (issue 33's priority).
#include "modules.h"

namespace cell::oracle {

namespace {
std::vector<const Module*> All() {
  return {&BaltModule(), &KtaplModule(), &EmcoModule(), &OkumaModule()};
}
}  // namespace

const Module* FindModule(const std::string& name) {
  for (const Module* m : All())
    if (m->Name() == name) return m;
  return nullptr;
}

std::vector<std::string> ModuleNames() {
  std::vector<std::string> names;
  for (const Module* m : All()) names.push_back(m->Name());
  return names;
}

}  // namespace cell::oracle
