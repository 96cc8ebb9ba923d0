// The page's DNC lines (docs/dashboard.md "DNC lines"): each station's serial line as its cell-dnc publishes
// it on cell/dnc/status, in its own part of the view so that the station cards stay as they are.
#include <nlohmann/json.hpp>

#include "cell/dashboard/cell_view.h"
#include "cell/records/time.h"

namespace cell::dashboard {

using nlohmann::json;

namespace {

// What the page shows first: a line whose cell-dnc is gone is "offline" (its last state is stale), an idle
// line whose last transfer failed is "error" until the next transfer begins; otherwise the transfer's state.
std::string PageState(const DncIn& d, bool online) {
  if (!online) return "offline";
  if (d.state == "idle" && d.failed) return "error";
  return d.state;
}

json RowJson(const DncIn& d, bool online) {
  return {{"station", d.station},
          {"device", d.device},
          {"state", PageState(d, online)},
          {"transfer_state", d.state},
          {"online", online},
          {"program", d.program},
          {"bytes", d.bytes},
          {"total", d.total},
          {"seconds", d.seconds},
          {"rate", d.rate},
          {"stopped_s", d.stopped_s},
          {"stalls", d.stalls},
          {"transfers", d.transfers},
          {"errors", d.errors},
          {"last_error", d.last_error},
          {"failed", d.failed},
          {"time", records::TimeOrNull(d.time_ns)}};
}

}  // namespace

void CellView::Dnc(const DncIn& d) {
  std::lock_guard lk(mu_);
  DncLine& line = dnc_[d.station];
  line.in = d;
  line.online = true;  // it wrote just now
  line.heard = std::chrono::steady_clock::now();
  Push({{"type", "dnc"}, {"dnc", RowJson(line.in, line.online)}});
}

void CellView::DncOnline(const std::string& station, bool online) {
  std::lock_guard lk(mu_);
  auto it = dnc_.find(station);
  if (it == dnc_.end() || it->second.online == online) return;
  // A new reader hears the line's state before the writer's heartbeat: not gone yet.
  const std::chrono::duration<double> age = std::chrono::steady_clock::now() - it->second.heard;
  if (!online && age.count() < opts_.dnc_grace_s) return;
  it->second.online = online;
  Push({{"type", "dnc"}, {"dnc", RowJson(it->second.in, online)}});
}

std::vector<std::string> CellView::DncStations() const {
  std::lock_guard lk(mu_);
  std::vector<std::string> out;
  for (auto& [station, line] : dnc_) out.push_back(station);
  return out;
}

json CellView::DncRows() const {
  json rows = json::array();
  for (auto& [station, line] : dnc_) rows.push_back(RowJson(line.in, line.online));
  return rows;
}

}  // namespace cell::dashboard
