#include "cell/tooltable/wire.h"

#include <string>

#include "cell/error/error.h"

namespace cell::tooltable {
namespace {

void CheckName(const std::string& tool) {
  if (tool.size() > 16) {
    throw Error(Errc::kInvalidArgument,
                "tool number '" + tool.substr(0, 20) + "...' longer than 16 characters");
  }
}

}  // namespace

cell::ToolTable ToWire(const ToolTable& t, std::string_view station, unsigned revision) {
  if (t.entries().size() > 512 || t.process_comps().size() > 512) {
    throw Error(Errc::kInvalidArgument, "tool table larger than 512 entries");
  }
  cell::ToolTable w;
  w.station(std::string(station));
  w.revision(revision);
  for (const ToolEntry& e : t.entries()) {
    CheckName(e.tool);
    cell::ToolEntry x;
    x.tool(e.tool);
    x.socket(e.socket);
    x.length(e.length);
    x.diameter(e.diameter);
    x.life_left_min(e.life_left_min);
    x.worn(e.worn);
    x.broken(e.broken);
    x.check(e.check);
    x.manual(e.manual);
    x.max_hp(e.max_hp);
    x.length_axis(e.length_axis);
    x.x_offset(e.x_offset);
    x.z_offset(e.z_offset);
    x.nose_radius(e.nose_radius);
    x.tip(e.tip);
    w.tools().push_back(x);
  }
  for (const ProcessComp& p : t.process_comps()) {
    CheckName(p.tool);
    cell::ProcessComp x;
    x.tool(p.tool);
    x.pallet(p.pallet);
    x.length(p.length);
    x.diameter(p.diameter);
    w.process().push_back(x);
  }
  return w;
}

ToolEntry FromWire(const cell::ToolEntry& x) {
  ToolEntry e;
  e.tool = x.tool().to_string();
  e.socket = x.socket();
  e.length = x.length();
  e.diameter = x.diameter();
  e.life_left_min = x.life_left_min();
  e.worn = x.worn();
  e.broken = x.broken();
  e.check = x.check();
  e.manual = x.manual();
  e.max_hp = x.max_hp();
  e.length_axis = x.length_axis() == 0 ? 'Z' : x.length_axis();
  e.x_offset = x.x_offset();
  e.z_offset = x.z_offset();
  e.nose_radius = x.nose_radius();
  e.tip = x.tip();
  return e;
}

ToolTable FromWire(const cell::ToolTable& w) {
  std::vector<ToolEntry> entries;
  std::vector<ProcessComp> process;
  for (const auto& x : w.tools()) entries.push_back(FromWire(x));
  for (const auto& x : w.process()) {
    process.push_back(ProcessComp{x.tool().to_string(), x.pallet(), x.length(), x.diameter()});
  }
  return ToolTable(std::move(entries), std::move(process));
}

}  // namespace cell::tooltable
