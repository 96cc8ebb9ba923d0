#include "cell/dashboard/mtconnect.h"

#include <fmt/format.h>

#include <cctype>
#include <functional>
#include <map>

#include "cell/records/time.h"

namespace cell::dashboard::mtc {

namespace {

constexpr const char* kVersion = "2.4.0.0";

// xs:ID is an NCName: a station id that starts with a digit or '-' gets a leading '_'.
std::string IdBase(const std::string& station) {
  if (!station.empty() && (std::isalpha(static_cast<unsigned char>(station[0])) || station[0] == '_'))
    return station;
  return "_" + station;
}

std::string Root(const char* doc) {
  return fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<MTConnect{0} xmlns=\"urn:mtconnect.org:MTConnect{0}:2.4\" "
      "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
      "xsi:schemaLocation=\"urn:mtconnect.org:MTConnect{0}:2.4 "
      "http://schemas.mtconnect.org/schemas/MTConnect{0}_2.4.xsd\">\n",
      doc);
}

std::string HeaderStart(const AgentInfo& a, bool model_time) {
  std::string h = fmt::format("  <Header creationTime=\"{}\" sender=\"{}\" instanceId=\"{}\" version=\"{}\"",
                              IsoTime(0), XmlEscape(a.sender), a.instance_id, kVersion);
  if (model_time) h += fmt::format(" deviceModelChangeTime=\"{}\"", IsoTime(a.model_time_ns));
  return h;
}

std::string Number(double v) {
  // Enough digits for positions (1 µm, 0.001 deg) without noise from the servo's doubles.
  std::string s = fmt::format("{:.4f}", v);
  while (s.size() > 1 && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

void WriteItem(std::string& out, const DataItem& d, const std::string& indent) {
  out += indent + fmt::format("<DataItem category=\"{}\" id=\"{}\" type=\"{}\"", d.category, d.id, d.type);
  if (!d.sub_type.empty()) out += fmt::format(" subType=\"{}\"", d.sub_type);
  if (!d.name.empty()) out += fmt::format(" name=\"{}\"", XmlEscape(d.name));
  if (!d.units.empty()) out += fmt::format(" units=\"{}\"", d.units);
  if (d.minimum_delta > 0 || d.period > 0) {
    out += ">\n" + indent + "  <Filters>\n";
    if (d.minimum_delta > 0)
      out +=
          indent + fmt::format("    <Filter type=\"MINIMUM_DELTA\">{}</Filter>\n", Number(d.minimum_delta));
    if (d.period > 0)
      out += indent + fmt::format("    <Filter type=\"PERIOD\">{}</Filter>\n", Number(d.period));
    out += indent + "  </Filters>\n" + indent + "</DataItem>\n";
  } else {
    out += "/>\n";
  }
}

}  // namespace

std::string IsoTime(std::int64_t ns) {
  return records::IsoTimeMicros(ns > 0 ? ns : records::NowNs());
}

std::string XmlEscape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        // XML 1.0 forbids most control characters even escaped: a space stands in for them.
        out += (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') ? ' ' : c;
    }
  }
  return out;
}

std::string AssetId(const ToolAsset& t) {
  return t.station + ".T" + t.tool;
}

DeviceModel::DeviceModel(std::vector<StationDef> stations) : stations_(std::move(stations)) {
  for (int s = 0; s < static_cast<int>(stations_.size()); ++s) {
    const StationDef& st = stations_[static_cast<size_t>(s)];
    const std::string b = IdBase(st.id);
    components_.push_back({s, "Device", b, st.id, ""});
    Add(s, b, {s, "avail", b + "_avail", "", "EVENT", "AVAILABILITY", "", "", "", "Availability"});
    Add(s, b, {s, "asset_chg", b + "_asset_chg", "", "EVENT", "ASSET_CHANGED", "", "", "", "AssetChanged"});
    Add(s, b, {s, "asset_rem", b + "_asset_rem", "", "EVENT", "ASSET_REMOVED", "", "", "", "AssetRemoved"});

    components_.push_back({s, "Axes", b + "_axes", "", b});
    bool has_c = false;
    for (const AxisDef& a : st.axes) {
      const std::string cid = b + "_" + a.name;
      components_.push_back({s, a.rotary ? "Rotary" : "Linear", cid, a.name, b + "_axes"});
      DataItem d{s,
                 "pos:" + a.name,
                 cid + "_pos",
                 "",
                 "SAMPLE",
                 a.rotary ? "ANGLE" : "POSITION",
                 "ACTUAL",
                 a.rotary ? "DEGREE" : "MILLIMETER",
                 "",
                 a.rotary ? "Angle" : "Position"};
      d.minimum_delta = 0.001;
      d.period = 0.1;
      Add(s, cid, d);
      if (a.name == "C") {
        has_c = true;
        Add(s, cid,
            {s, "spindle_speed", cid + "_speed", "", "SAMPLE", "ROTARY_VELOCITY", "ACTUAL",
             "REVOLUTION/MINUTE", "S", "RotaryVelocity", 1, 0.1});
        Add(s, cid, {s, "spindle_mode", cid + "_mode", "", "EVENT", "ROTARY_MODE", "", "", "", "RotaryMode"});
      }
    }
    if (!has_c) {
      // The spindle turns about Z on both machining centres and lathes: Rotary C in SPINDLE mode.
      const std::string cid = b + "_C";
      components_.push_back({s, "Rotary", cid, "C", b + "_axes"});
      Add(s, cid,
          {s, "spindle_speed", cid + "_speed", "", "SAMPLE", "ROTARY_VELOCITY", "ACTUAL", "REVOLUTION/MINUTE",
           "S", "RotaryVelocity", 1, 0.1});
      Add(s, cid, {s, "spindle_mode", cid + "_mode", "", "EVENT", "ROTARY_MODE", "", "", "", "RotaryMode"});
    }
    if (st.live_tool) {
      // A lathe's live-tool (M-tool) spindle is a second spindle: a Rotary of its own, its speed named SB as
      // Okuma's address.
      const std::string cid = b + "_LT";
      components_.push_back({s, "Rotary", cid, "LT", b + "_axes"});
      Add(s, cid,
          {s, "live_tool_speed", cid + "_speed", "", "SAMPLE", "ROTARY_VELOCITY", "ACTUAL",
           "REVOLUTION/MINUTE", "SB", "RotaryVelocity", 1, 0.1});
      Add(s, cid, {s, "live_tool_mode", cid + "_mode", "", "EVENT", "ROTARY_MODE", "", "", "", "RotaryMode"});
    }

    components_.push_back({s, "Controller", b + "_ctrl", "controller", b});
    const std::string p = b + "_path";
    components_.push_back({s, "Path", p, "path", b + "_ctrl"});
    Add(s, p, {s, "exec", p + "_exec", "", "EVENT", "EXECUTION", "", "", "", "Execution"});
    Add(s, p, {s, "mode", p + "_mode", "", "EVENT", "CONTROLLER_MODE", "", "", "", "ControllerMode"});
    Add(s, p, {s, "program", p + "_program", "", "EVENT", "PROGRAM", "", "", "", "Program"});
    Add(s, p, {s, "line", p + "_line", "", "EVENT", "LINE_NUMBER", "ABSOLUTE", "", "Line", "LineNumber"});
    Add(s, p, {s, "parts", p + "_parts", "", "EVENT", "PART_COUNT", "", "", "", "PartCount"});
    Add(s, p, {s, "tool", p + "_tool", "", "EVENT", "TOOL_NUMBER", "", "", "", "ToolNumber"});
    Add(s, p, {s, "pallet", p + "_pallet", "", "EVENT", "PALLET_ID", "", "", "", "PalletId"});
    Add(s, p, {s, "message", p + "_message", "", "EVENT", "MESSAGE", "", "", "", "Message"});
    DataItem feed{s,        "feed",          p + "_feed", "",
                  "SAMPLE", "PATH_FEEDRATE", "ACTUAL",    "MILLIMETER/SECOND",
                  "",       "PathFeedrate"};
    feed.minimum_delta = 0.01;
    feed.period = 0.1;
    Add(s, p, feed);
    Add(s, p, {s, "system", p + "_system", "", "CONDITION", "SYSTEM", "", "", "", "System"});
  }
}

void DeviceModel::Add(int station, const std::string& component, DataItem d) {
  d.station = station;
  d.component = component;
  items_.push_back(std::move(d));
}

int DeviceModel::Find(int station, std::string_view key) const {
  for (size_t i = 0; i < items_.size(); ++i)
    if (items_[i].station == station && items_[i].key == key) return static_cast<int>(i);
  return -1;
}

int DeviceModel::StationIndex(std::string_view id) const {
  for (size_t i = 0; i < stations_.size(); ++i)
    if (stations_[i].id == id) return static_cast<int>(i);
  return -1;
}

std::string Devices(const AgentInfo& a, const DeviceModel& m, int device, std::size_t asset_count) {
  std::string out = Root("Devices");
  out += HeaderStart(a, true) + fmt::format(" bufferSize=\"{}\" assetBufferSize=\"{}\" assetCount=\"{}\"/>\n",
                                            a.buffer_size, a.asset_buffer_size, asset_count);
  out += "  <Devices>\n";
  const auto& comps = m.components();
  // Components nest by parent id; each component writes its data items, then its children.
  std::function<void(const Component&, const std::string&)> write = [&](const Component& c,
                                                                        const std::string& ind) {
    if (c.element == "Device") {
      const StationDef& st = m.stations()[static_cast<size_t>(c.station)];
      out += ind + fmt::format("<Device id=\"{}\" uuid=\"{}\" name=\"{}\">\n", c.id, XmlEscape(st.id),
                               XmlEscape(st.id));
      out += ind + fmt::format("  <Description>{}</Description>\n",
                               XmlEscape(st.description.empty() ? st.dialect + " station" : st.description));
    } else {
      out += ind + "<" + c.element + " id=\"" + c.id + "\"";
      if (!c.name.empty()) out += " name=\"" + XmlEscape(c.name) + "\"";
      out += ">\n";
    }
    bool any = false;
    for (const auto& d : m.items()) {
      if (d.component != c.id) continue;
      if (!any) out += ind + "  <DataItems>\n";
      any = true;
      WriteItem(out, d, ind + "    ");
    }
    if (any) out += ind + "  </DataItems>\n";
    bool kids = false;
    for (const auto& k : comps) {
      if (k.parent != c.id || k.station != c.station) continue;
      if (!kids) out += ind + "  <Components>\n";
      kids = true;
      write(k, ind + "    ");
    }
    if (kids) out += ind + "  </Components>\n";
    out += ind + "</" + c.element + ">\n";
  };
  for (const auto& c : comps)
    if (c.element == "Device" && (device < 0 || c.station == device)) write(c, "    ");
  out += "  </Devices>\n</MTConnectDevices>\n";
  return out;
}

std::string Streams(const AgentInfo& a, const DeviceModel& m, const std::vector<const Observation*>& obs,
                    std::uint64_t first, std::uint64_t last, std::uint64_t next, int device) {
  std::string out = Root("Streams");
  out += HeaderStart(a, true) + fmt::format(
                                    " bufferSize=\"{}\" nextSequence=\"{}\" firstSequence=\"{}\" "
                                    "lastSequence=\"{}\"/>\n",
                                    a.buffer_size, next, first, last);
  out += "  <Streams>\n";
  const auto& items = m.items();
  for (int s = 0; s < static_cast<int>(m.stations().size()); ++s) {
    if (device >= 0 && s != device) continue;
    const StationDef& st = m.stations()[static_cast<size_t>(s)];
    out += fmt::format("    <DeviceStream name=\"{0}\" uuid=\"{0}\">\n", XmlEscape(st.id));
    for (const auto& c : m.components()) {
      if (c.station != s) continue;
      std::string parts[3];  // Samples, Events, Condition: the schema's order
      for (const Observation* o : obs) {
        const DataItem& d = items[static_cast<size_t>(o->item)];
        if (d.component != c.id) continue;
        const std::string attrs = fmt::format("dataItemId=\"{}\" timestamp=\"{}\" sequence=\"{}\"", d.id,
                                              IsoTime(o->time_ns), o->sequence);
        if (d.category == "CONDITION") {
          std::string level = o->level.empty() ? "Unavailable" : o->level;
          if (level == "NORMAL") level = "Normal";
          if (level == "WARNING") level = "Warning";
          if (level == "FAULT") level = "Fault";
          if (level == "UNAVAILABLE") level = "Unavailable";
          std::string el = "        <" + level + " " + attrs + " type=\"" + d.type + "\"";
          if (!o->native_code.empty()) el += " nativeCode=\"" + XmlEscape(o->native_code) + "\"";
          // 2.x: an active condition names its instance (one alarm code, one instance).
          if (level == "Fault" || level == "Warning")
            el += " conditionId=\"" + XmlEscape(o->native_code.empty() ? d.id : o->native_code) + "\"";
          if (o->value.empty())
            el += "/>\n";
          else
            el += ">" + XmlEscape(o->value) + "</" + level + ">\n";
          parts[2] += el;
          continue;
        }
        std::string extra;
        if (!d.sub_type.empty()) extra += " subType=\"" + d.sub_type + "\"";
        if (!d.name.empty()) extra += " name=\"" + XmlEscape(d.name) + "\"";
        if (d.type == "ASSET_CHANGED" || d.type == "ASSET_REMOVED") extra += " assetType=\"CuttingTool\"";
        std::string value = o->value.empty() ? "UNAVAILABLE" : o->value;
        parts[d.category == "SAMPLE" ? 0 : 1] +=
            "        <" + d.element + " " + attrs + extra + ">" + XmlEscape(value) + "</" + d.element + ">\n";
      }
      if (parts[0].empty() && parts[1].empty() && parts[2].empty()) continue;
      out += fmt::format("      <ComponentStream component=\"{}\" componentId=\"{}\"", c.element, c.id);
      if (!c.name.empty()) out += " name=\"" + XmlEscape(c.name) + "\"";
      out += ">\n";
      if (!parts[0].empty()) out += "        <Samples>\n" + parts[0] + "        </Samples>\n";
      if (!parts[1].empty()) out += "        <Events>\n" + parts[1] + "        </Events>\n";
      if (!parts[2].empty()) out += "        <Condition>\n" + parts[2] + "        </Condition>\n";
      out += "      </ComponentStream>\n";
    }
    out += "    </DeviceStream>\n";
  }
  out += "  </Streams>\n</MTConnectStreams>\n";
  return out;
}

std::string Assets(const AgentInfo& a, const std::vector<ToolAsset>& tools) {
  std::string out = Root("Assets");
  out += HeaderStart(a, true) +
         fmt::format(" assetBufferSize=\"{}\" assetCount=\"{}\"/>\n", a.asset_buffer_size, tools.size());
  out += "  <Assets>\n";
  for (const auto& t : tools) {
    const char* status = t.broken ? "BROKEN" : t.worn ? "EXPIRED" : "AVAILABLE";
    out += fmt::format(
        "    <CuttingTool assetId=\"{}\" serialNumber=\"{}\" toolId=\"{}\" deviceUuid=\"{}\" "
        "timestamp=\"{}\">\n",
        XmlEscape(AssetId(t)), XmlEscape(t.tool), XmlEscape(t.tool), XmlEscape(t.station),
        IsoTime(t.time_ns));
    out += "      <CuttingToolLifeCycle>\n";
    out += fmt::format("        <CutterStatus><Status>{}</Status></CutterStatus>\n", status);
    out += fmt::format("        <ToolLife type=\"MINUTES\" countDirection=\"DOWN\">{}</ToolLife>\n",
                       Number(t.life_left_min));
    // The program's T number is the tool's base number; "33412.5" is data set 5 of tool 33412 (KT-APL TLD).
    out += fmt::format("        <ProgramToolNumber>{}</ProgramToolNumber>\n",
                       XmlEscape(t.tool.substr(0, t.tool.find('.'))));
    out += fmt::format("        <Location type=\"POT\">{}</Location>\n", t.socket);
    out += "        <Measurements>\n";
    out += fmt::format("          <FunctionalLength code=\"LF\" units=\"MILLIMETER\">{}</FunctionalLength>\n",
                       Number(t.length));
    out += fmt::format(
        "          <CuttingDiameterMax code=\"DC\" units=\"MILLIMETER\">{}</CuttingDiameterMax>\n",
        Number(t.diameter));
    out += "        </Measurements>\n";
    out += "      </CuttingToolLifeCycle>\n";
    out += "    </CuttingTool>\n";
  }
  out += "  </Assets>\n</MTConnectAssets>\n";
  return out;
}

std::string Error(const AgentInfo& a, std::string_view code, std::string_view text) {
  std::string out = Root("Error");
  out += HeaderStart(a, false) + fmt::format(" bufferSize=\"{}\"/>\n", a.buffer_size);
  out += fmt::format("  <Errors>\n    <Error errorCode=\"{}\">{}</Error>\n  </Errors>\n</MTConnectError>\n",
                     code, XmlEscape(text));
  return out;
}

}  // namespace cell::dashboard::mtc
