#include "cell/station/panel.h"

#include <set>

#include <spdlog/spdlog.h>

#include "cell/error/error.h"
#include "cell/names/names.h"

namespace cell::station {

StatusBoard::StatusBoard(const std::string& station, const std::string& dialect, Clock& clock,
                         std::function<void(const cell::StationStatus&)> publish)
    : clock_(clock), publish_(std::move(publish)) {
  status_.station(station);
  status_.dialect(dialect);
  status_.condition(cell::CONDITION_NORMAL);
  Show();
}

void StatusBoard::Show() {
  status_.execution(held_ ? cell::EXECUTION_FEED_HOLD : base_);
}

void StatusBoard::Queued(int n) {
  std::lock_guard lk(mu_);
  status_.queued(n);
}

void StatusBoard::RunStarted(std::int32_t pallet, std::int32_t dispatch_id) {
  std::lock_guard lk(mu_);
  base_ = cell::EXECUTION_ACTIVE;
  Show();
  message_.clear();
  status_.status_text("");
  status_.pallet(pallet);
  status_.dispatch_id(dispatch_id);
}

void StatusBoard::RunEnded(bool completed, int queued) {
  std::lock_guard lk(mu_);
  base_ = completed ? cell::EXECUTION_PROGRAM_COMPLETED : cell::EXECUTION_STOPPED;
  Show();
  status_.status_text("");
  message_.clear();
  status_.part_count(status_.part_count() + (completed ? 1 : 0));
  status_.dispatch_id(0);
  status_.queued(queued);
}

void StatusBoard::Position(const std::string& program, int line, const std::string* tool) {
  std::lock_guard lk(mu_);
  names::Assign(status_.program(), program, "program name");
  status_.line(line);
  if (tool) status_.tool(tool->substr(0, 16));
}

void StatusBoard::Waiting(const std::string& text, cell::Execution execution) {
  std::lock_guard lk(mu_);
  base_ = text.empty() ? cell::EXECUTION_ACTIVE : execution;
  Show();
  status_.status_text((text.empty() ? message_ : text).substr(0, 255));
}

void StatusBoard::Message(const std::string& text) {
  std::lock_guard lk(mu_);
  message_ = text;
  if (base_ == cell::EXECUTION_ACTIVE) status_.status_text(text.substr(0, 255));
}

std::string StatusBoard::LastMessage() const {
  std::lock_guard lk(mu_);
  return message_;
}

void StatusBoard::Warning(const std::string& code, const std::string& text) {
  std::lock_guard lk(mu_);
  status_.condition(cell::CONDITION_WARNING);
  status_.alarm_code(code.substr(0, 16));
  status_.alarm_text(text.substr(0, 255));
}

void StatusBoard::Reset() {
  std::lock_guard lk(mu_);
  status_.condition(cell::CONDITION_NORMAL);
  status_.alarm_code("");
  status_.alarm_text("");
}

void StatusBoard::ServoHeld(bool held) {
  std::lock_guard lk(mu_);
  if (held == held_) return;
  held_ = held;
  Show();
  Send();
}

void StatusBoard::Publish() {
  std::lock_guard lk(mu_);
  Send();
}

void StatusBoard::PublishChanged() {
  std::lock_guard lk(mu_);
  sent_.updated_ns(status_.updated_ns());
  if (sent_ != status_) Send();
}

void StatusBoard::Send() {
  status_.updated_ns(clock_.WallNs());
  sent_ = status_;
  publish_(status_);
}

cell::StationStatus StatusBoard::Get() const {
  std::lock_guard lk(mu_);
  return status_;
}

Panel::Panel(const std::string& station, StationDb& db,
             std::function<void(const cell::ServoControl&)> publish)
    : db_(db), publish_(std::move(publish)) {
  const PanelState p = db_.LoadPanel();
  control_.station(station);
  control_.feed_hold(p.feed_hold);
  control_.feed_override(p.feed_override);
  control_.rapid_override(p.rapid_override);
  control_.broken_sockets().assign(p.broken_sockets.begin(), p.broken_sockets.end());
  optional_stop_ = p.optional_stop;
}

// The servo reports the hold in its progress, which turns the displayed execution to FEED_HOLD and back
// (StatusBoard::ServoHeld); pressing does not wait for that.
std::uint32_t Panel::Press(const cell::StationRequest& r) {
  std::lock_guard lk(mu_);
  cell::ServoControl c = control_;
  if (r.op() == cell::STATION_OVERRIDE) {
    if (r.feed_override() > 2.0 || r.rapid_override() > 1.0)
      throw Error(Errc::kInvalidArgument, "feed override is 0..200 %, rapid override 0..100 %");
    if (r.feed_override() >= 0) c.feed_override(r.feed_override());
    if (r.rapid_override() >= 0) c.rapid_override(r.rapid_override());
  } else if (r.op() == cell::STATION_FEED_HOLD || r.op() == cell::STATION_CYCLE_START) {
    c.feed_hold(r.op() == cell::STATION_FEED_HOLD);
    if (r.op() == cell::STATION_CYCLE_START) ++cycle_starts_;
  } else if (r.op() == cell::STATION_OPTIONAL_STOP) {
    optional_stop_ = r.optional_stop();  // read by the next program (its M01s)
  } else if (r.op() == cell::STATION_BREAK_TOOL) {
    // The operator's word for the tool model of the machine: a G38 check finds the tool there broken (or,
    // mended, whole again); the tool table's own broken flag is the control's, set by that check.
    if (r.socket() < 1 || r.socket() > 1000) throw Error(Errc::kInvalidArgument, "a socket is 1..1000");
    std::set<int> broken(c.broken_sockets().begin(), c.broken_sockets().end());
    if (r.mend()) {
      broken.erase(r.socket());
    } else {
      broken.insert(r.socket());
    }
    if (broken.size() > 64) throw Error(Errc::kInvalidArgument, "at most 64 sockets can be broken at once");
    c.broken_sockets().assign(broken.begin(), broken.end());
  } else {
    throw Error(Errc::kInvalidArgument, "not a panel button");
  }
  c.revision(c.revision() + 1);
  PanelState saved;
  saved.feed_hold = c.feed_hold();
  saved.feed_override = c.feed_override();
  saved.rapid_override = c.rapid_override();
  saved.broken_sockets.insert(c.broken_sockets().begin(), c.broken_sockets().end());
  saved.optional_stop = optional_stop_;
  db_.SavePanel(saved);
  control_ = c;
  publish_(Sent());
  spdlog::info("panel: feed hold {}, feed override {:.0f} %{}, rapid override {:.0f} %",
               c.feed_hold() ? "on" : "off", c.feed_override() * 100,
               overrides_fixed_ ? " (fixed at 100 % by the program)" : "", c.rapid_override() * 100);
  return c.revision();
}

std::optional<bool> Panel::OptionalStop() const {
  std::lock_guard lk(mu_);
  return optional_stop_;
}

std::uint64_t Panel::CycleStarts() const {
  std::lock_guard lk(mu_);
  return cycle_starts_;
}

void Panel::AbortRun(std::int32_t run_id) {
  std::lock_guard lk(mu_);
  control_.abort_run(run_id);
  control_.revision(control_.revision() + 1);
  publish_(Sent());
}

void Panel::FixOverrides(bool fixed) {
  std::lock_guard lk(mu_);
  if (fixed == overrides_fixed_) return;
  overrides_fixed_ = fixed;
  control_.revision(control_.revision() + 1);
  publish_(Sent());
  spdlog::info("panel: feed and spindle speed {}",
               fixed ? "fixed at 100 % by the program (KT-APL M49, Okuma M161)" : "overrides enabled again");
}

cell::ServoControl Panel::Sent() const {
  cell::ServoControl c = control_;
  if (overrides_fixed_ && c.feed_override() > 0) c.feed_override(1.0);
  return c;
}

void Panel::Publish() {
  std::lock_guard lk(mu_);
  publish_(Sent());
}

cell::ServoControl Panel::Get() const {
  std::lock_guard lk(mu_);
  return Sent();
}

}  // namespace cell::station
