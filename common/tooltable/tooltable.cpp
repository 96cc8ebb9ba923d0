#include "cell/tooltable/tooltable.h"

#include <algorithm>
#include <cctype>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "cell/error/error.h"

namespace cell::tooltable {
namespace {

char Upper(char c) {
  return static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
}
bool IsDigit(char c) {
  return c >= '0' && c <= '9';
}

}  // namespace

std::string NormalizeToolNumber(std::string_view text) {
  std::string_view s = text;
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  if (!s.empty() && Upper(s.front()) == 'T') s.remove_prefix(1);
  std::string_view number = s, suffix;
  if (auto dot = s.find('.'); dot != std::string_view::npos) {
    number = s.substr(0, dot);
    suffix = s.substr(dot + 1);
  }
  const auto all_digits = [](std::string_view v) {
    return !v.empty() && std::all_of(v.begin(), v.end(), [](char c) { return IsDigit(c); });
  };
  if (!all_digits(number) || number.size() > 7) {
    throw Error(Errc::kInvalidArgument, "bad tool number '" + std::string(text) + "' (1-7 digits expected)");
  }
  if (s.find('.') != std::string_view::npos &&
      (suffix.size() != 1 || !all_digits(suffix) || suffix[0] < '0' || suffix[0] > '7')) {
    throw Error(Errc::kInvalidArgument, "bad tool suffix in '" + std::string(text) + "' (.1-.7 expected)");
  }
  while (number.size() > 1 && number.front() == '0') number.remove_prefix(1);
  std::string out(number);
  if (!suffix.empty() && suffix != "0") out += "." + std::string(suffix);
  return out;
}

std::string_view BaseTool(std::string_view tool) {
  return tool.substr(0, tool.find('.'));
}

ToolTable::ToolTable(std::vector<ToolEntry> entries, std::vector<ProcessComp> process)
    : entries_(std::move(entries)), process_(std::move(process)) {}

const ToolEntry* ToolTable::Find(std::string_view tool, int socket) const {
  const ToolEntry* first = nullptr;
  for (const auto& e : entries_) {
    if (e.tool != tool) continue;
    if (socket <= 0 || e.socket == socket) return &e;
    if (!first) first = &e;
  }
  return socket > 0 ? nullptr : first;
}

ToolEntry* ToolTable::Find(std::string_view tool, int socket) {
  return const_cast<ToolEntry*>(std::as_const(*this).Find(tool, socket));
}

void ToolTable::Upsert(const ToolEntry& entry) {
  ToolEntry* same = nullptr;   // this number in this socket
  ToolEntry* other = nullptr;  // this number, where a new socket does not make it an alternate
  bool in_other_socket = false;
  for (auto& e : entries_) {
    if (e.tool != entry.tool) continue;
    if (e.socket == entry.socket) {
      same = &e;
      break;
    }
    if (e.socket > 0 && entry.socket > 0) {
      in_other_socket = true;
    } else if (!other) {
      other = &e;
    }
  }
  if (same) {
    *same = entry;
  } else if (other && !in_other_socket) {
    *other = entry;
  } else {
    entries_.push_back(entry);
  }
}

const ToolEntry* ToolTable::Select(std::string_view tool, bool* exists) const {
  bool any = false;
  for (const auto& e : entries_) {
    if (e.tool != tool) continue;
    any = true;
    if (Usable(e)) {
      if (exists) *exists = true;
      return &e;
    }
  }
  if (exists) *exists = any;
  return nullptr;
}

bool ToolTable::Charge(const ToolWear& wear) {
  ToolEntry* e = Find(wear.tool, wear.socket);
  if (!e && wear.socket > 0) e = Find(wear.tool);
  if (!e) return false;
  if (wear.cutting_s > 0 && e->life_left_min > 0) {
    e->life_left_min = std::max(0.0, e->life_left_min - wear.cutting_s / 60.0);
    if (e->life_left_min <= 0) e->worn = true;
  }
  if (wear.broken) e->broken = true;
  return true;
}

bool ToolTable::UpsertProcess(const ProcessComp& comp) {
  if (Find(comp.tool) == nullptr) return false;
  auto it = std::find_if(process_.begin(), process_.end(), [&](const ProcessComp& p) {
    return p.tool == comp.tool && p.pallet == comp.pallet;
  });
  if (it != process_.end()) {
    *it = comp;
  } else {
    process_.push_back(comp);
  }
  return true;
}

void ToolTable::Clear() {
  entries_.clear();
  process_.clear();
}

bool ToolTable::Effective(std::string_view tool, int pallet, Compensation* out, int socket) const {
  const ToolEntry* e = Find(tool, socket);
  if (e == nullptr && socket > 0) e = Find(tool);
  if (e == nullptr) return false;
  Compensation c{e->length, e->diameter};
  if (pallet != 0) {
    for (const auto& p : process_) {
      if (p.tool == tool && p.pallet == pallet) {
        c.length += p.length;
        c.diameter += p.diameter;
      }
    }
  }
  *out = c;
  return true;
}

bool ToolTable::Holds(std::string_view tool) const {
  const bool want_suffix = tool.find('.') != std::string_view::npos;
  for (const auto& e : entries_) {
    if (!Usable(e)) continue;
    if (want_suffix ? e.tool == tool : BaseTool(e.tool) == tool) return true;
  }
  return false;
}

nlohmann::json EntryJson(const ToolEntry& e) {
  nlohmann::json j = {{"tool", e.tool},
                      {"socket", e.socket},
                      {"length", e.length},
                      {"diameter", e.diameter},
                      {"life_left_min", e.life_left_min},
                      {"worn", e.worn},
                      {"broken", e.broken},
                      {"check", e.check},
                      {"manual", e.manual},
                      {"max_hp", e.max_hp}};
  if (e.length_axis != 'Z') j["length_axis"] = std::string(1, e.length_axis);
  if (e.x_offset != 0 || e.z_offset != 0 || e.nose_radius != 0 || e.tip != 0) {
    j["x_offset"] = e.x_offset;
    j["z_offset"] = e.z_offset;
    j["nose_radius"] = e.nose_radius;
    j["tip"] = e.tip;
  }
  return j;
}

ToolEntry EntryFromJson(const nlohmann::json& j) {
  try {
    ToolEntry e;
    e.tool = j.at("tool").get<std::string>();
    e.socket = j.value("socket", 0);
    e.length = j.value("length", 0.0);
    e.diameter = j.value("diameter", 0.0);
    e.life_left_min = j.value("life_left_min", 0.0);
    e.worn = j.value("worn", false);
    e.broken = j.value("broken", false);
    e.check = j.value("check", false);
    e.manual = j.value("manual", false);
    e.max_hp = j.value("max_hp", 0.0);
    std::string axis = j.value("length_axis", std::string("Z"));
    e.length_axis = axis.size() == 1 ? Upper(axis[0]) : 'Z';
    e.x_offset = j.value("x_offset", 0.0);
    e.z_offset = j.value("z_offset", 0.0);
    e.nose_radius = j.value("nose_radius", 0.0);
    e.tip = j.value("tip", 0);
    return e;
  } catch (const nlohmann::json::exception& ex) {
    throw Error(Errc::kInvalidArgument, std::string("malformed tool entry: ") + ex.what());
  }
}

nlohmann::json ToJson(const ToolTable& t) {
  nlohmann::json entries = nlohmann::json::array(), process = nlohmann::json::array();
  for (const auto& e : t.entries()) entries.push_back(EntryJson(e));
  for (const auto& p : t.process_comps()) {
    process.push_back(
        {{"tool", p.tool}, {"pallet", p.pallet}, {"length", p.length}, {"diameter", p.diameter}});
  }
  return {{"entries", entries}, {"process", process}};
}

ToolTable FromJson(const nlohmann::json& j) {
  std::vector<ToolEntry> entries;
  std::vector<ProcessComp> process;
  try {
    for (const auto& e : j.at("entries")) entries.push_back(EntryFromJson(e));
    for (const auto& p : j.value("process", nlohmann::json::array())) {
      process.push_back(ProcessComp{p.at("tool").get<std::string>(), p.at("pallet").get<int>(),
                                    p.value("length", 0.0), p.value("diameter", 0.0)});
    }
  } catch (const nlohmann::json::exception& ex) {
    throw Error(Errc::kInvalidArgument, std::string("malformed tool table: ") + ex.what());
  }
  return ToolTable(std::move(entries), std::move(process));
}

}  // namespace cell::tooltable
