#include "cell/station/segment_stream.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <vector>

#include "cell/error/error.h"

namespace cell::station {

SegmentStream::SegmentStream(std::string station, Clock& clock, ServoLink& link)
    : station_(std::move(station)), clock_(clock), link_(link) {}

void SegmentStream::Begin(std::int32_t run_id, std::function<void()> checkpoint) {
  std::lock_guard lk(mu_);
  checkpoint_ = std::move(checkpoint);
  run_id_ = run_id;
  sent_seq_ = completed_seq_ = received_seq_ = 0;
  credit_seq_ = kInitialCredit;
  run_machine_s_ = 0;
  alarm_ = false;
  alarm_code_.clear();
  alarm_text_.clear();
  servo_restarted_ = false;
  rejoined_ = false;
  unmatched_since_.reset();
  run_boot_ = 0;
  unacked_.clear();
  probes_.clear();
  cut_.clear();
  matches_ = link_.TotalMatched();
  last_progress_ = last_report_ = last_resend_ = clock_.Now();
}

void SegmentStream::Send(cell::MotionSegment seg) {
  std::unique_lock lk(mu_);
  seg.station(station_);
  seg.run_id(run_id_);
  seg.seq(++sent_seq_);
  last_progress_ = clock_.Now();
  WaitCredit(lk, seg.seq());
  ResendMissing(lk);  // the earlier segments first: the servo takes them in seq order only
  // A servo that had taken everything owed no report: its silence counts from this segment, not from its last
  // report before the run waited (an input, a writer) for longer than kServoGone.
  if (received_seq_ + 1 >= seg.seq()) last_report_ = clock_.Now();
  unacked_.push_back(seg);
  lk.unlock();
  link_.Write(seg);
}

void SegmentStream::SendPart(cell::PartModel part) {
  std::unique_lock lk(mu_);
  part.station(station_);
  part.run_id(run_id_);
  lk.unlock();
  link_.WritePart(part);
  lk.lock();
  auto deadline = clock_.Now() + kServoGone;
  while (servo_part_run_ != run_id_) {
    Check(lk);
    if (clock_.Now() > deadline) {
      if (!RejoinOnce(lk, "has not taken the part model"))
        throw Error(Errc::kUnavailable, fmt::format("axis servo of {} did not take part model {} within {} s",
                                                    station_, part.name().to_string(), kServoGone.count()));
      lk.unlock();  // the new participant's writer holds no part model yet
      link_.WritePart(part);
      lk.lock();
      deadline = clock_.Now() + kServoGone;
      continue;
    }
    clock_.Wait(lk, cv_, kPoll);
  }
}

cell::ProbeResult SegmentStream::Probe(cell::MotionSegment seg) {
  seg.kind(cell::SEGMENT_PROBE);
  seg.waits(true);  // nothing follows until its result is in
  Send(seg);
  std::unique_lock lk(mu_);
  const std::uint64_t want = sent_seq_;
  const auto deadline = clock_.Now() + kProbeTimeout;
  while (!probes_.count(want)) {
    Check(lk);  // alarms, a lost servo, and the re-send after it matched again
    if (clock_.Now() > deadline) throw Error(Errc::kTimeout, "no probe result from the axis servo");
    clock_.Wait(lk, cv_, kPoll);
  }
  cell::ProbeResult r = probes_[want];
  probes_.erase(want);
  return r;
}

void SegmentStream::WaitDrained() {
  std::unique_lock lk(mu_);
  if (completed_seq_ < sent_seq_ && !unacked_.empty() && !unacked_.back().waits() &&
      unacked_.back().kind() != cell::SEGMENT_END) {
    // Tell a virtual-clock servo that nothing more comes until these are done: its look-ahead runs on at
    // once instead of waiting for a refill (the last segment again, flagged; the servo keeps the flag only).
    // After END it runs on anyway.
    unacked_.back().waits(true);
    const cell::MotionSegment again = unacked_.back();
    lk.unlock();  // never write under the lock
    link_.Write(again);
    lk.lock();
  }
  while (completed_seq_ < sent_seq_) {
    Check(lk);
    clock_.Wait(lk, cv_, kPoll);
  }
}

void SegmentStream::WaitUntil(const std::function<bool()>& ready) {
  std::unique_lock lk(mu_);
  for (;;) {
    Check(lk);
    lk.unlock();
    const bool done = ready();
    lk.lock();
    if (done) return;
    clock_.Wait(lk, cv_, kPoll);
  }
}

// Credit-based flow control: never more segments in flight than the servo granted.
void SegmentStream::WaitCredit(std::unique_lock<std::mutex>& lk, std::uint64_t seq) {
  while (seq > credit_seq_) {
    Check(lk);
    clock_.Wait(lk, cv_, kPoll);
  }
}

// While waiting on the servo: end the run on a cancel or stop (checkpoint), an alarm, a restarted or vanished
// servo; re-send what it may have missed when it matched again.
void SegmentStream::Check(std::unique_lock<std::mutex>& lk) {
  if (checkpoint_) {
    lk.unlock();  // the checkpoint may take other locks
    checkpoint_();
    lk.lock();
  }
  if (alarm_) throw Error(Errc::kFailedPrecondition, "[" + alarm_code_ + "] " + alarm_text_);
  if (servo_restarted_)
    throw Error(Errc::kUnavailable, "axis servo of " + station_ + " restarted during the run");
  const auto now = clock_.Now();
  // Vanished: unmatched for kServoGone, counted from when the match was lost (or the last progress, if
  // later). Counted from the progress alone, a servo stopped past its lease during a long feed hold (it
  // says nothing while held) was vanished the moment the lease ran out, though back 0.5 s later (fms_test
  // under ASan beside the chaos test).
  if (link_.Matched() > 0) {
    unmatched_since_.reset();
  } else {
    if (!unmatched_since_) unmatched_since_ = now;
    if (now - std::max(*unmatched_since_, last_progress_) > kServoGone)
      throw Error(Errc::kUnavailable, "axis servo of " + station_ + " vanished during the run");
  }
  // Matched on this side but deaf on the other (Fast DDS 2.9 may not re-exchange endpoints after only one
  // side let the lease run out, docs/operations.md): segments are missing and nothing comes back.
  if (!unacked_.empty() && received_seq_ < unacked_.back().seq() && now - last_report_ > kServoGone &&
      !RejoinOnce(lk, "has taken no segment"))
    throw Error(Errc::kUnavailable, "axis servo of " + station_ + " has taken no segment for " +
                                        std::to_string(kServoGone.count()) + " s");
  ResendMissing(lk);
}

// A servo not matched at a run's start is most often, on a loaded host, one whose discovery with this process
// broke one way, as below: in a 32-station Fast DDS week, EM05's interpreter never matched its restarted
// servo and failed six pallets in five minutes while both processes ran. So before the run fails, this
// process joins the bus anew once and waits as long again.
bool SegmentStream::WaitForServo(Clock::Duration timeout) {
  if (link_.WaitForServo(timeout)) return true;
  spdlog::warn("no axis servo of {} matched within {} s: joining the bus anew", station_,
               std::chrono::duration_cast<std::chrono::seconds>(timeout).count());
  link_.Rejoin();
  return link_.WaitForServo(timeout);
}

// A servo matched on this side that says nothing for kServoGone is most often one DDS discovery broke one
// way (Fast DDS 2.9's one-sided lease expiry under load: a chaos run's station stayed so until restarted,
// failing every run). Once a run, this process joins the bus anew, so discovery with the servo starts clean,
// and the run waits kServoGone more: the re-send after the new match brings the servo what it missed, in
// order. True when it did so now; false when this run already had its rejoin (then the run fails).
bool SegmentStream::RejoinOnce(std::unique_lock<std::mutex>& lk, const char* why) {
  if (rejoined_) return false;
  rejoined_ = true;
  spdlog::warn("axis servo of {} {} for {} s though matched (run {}): joining the bus anew", station_, why,
               kServoGone.count(), run_id_);
  lk.unlock();  // the rejoin re-creates the reader whose callback takes the lock
  link_.Rejoin();
  lk.lock();
  // The silence, and a lost match, count from the new participant.
  last_report_ = last_progress_ = clock_.Now();
  unmatched_since_.reset();
  return true;
}

// The segment stream is volatile: what is written while the servo is unmatched (its process stopped past the
// DDS lease, a network cut) never arrives, and a servo that dropped the match on its side may miss samples
// the writer still thinks delivered. So segments are kept until completed and sent again, in order, from
// the first one the servo has not reported (received_seq), when the writer matches a servo again or when
// the servo has been silent for a second with segments missing. The servo drops what it already holds.
void SegmentStream::ResendMissing(std::unique_lock<std::mutex>& lk) {
  if (unacked_.empty() || link_.Matched() == 0) return;
  const auto now = clock_.Now();
  const std::uint64_t matches = link_.TotalMatched();
  const bool rematched = matches != matches_;
  const bool silent = received_seq_ < unacked_.back().seq() && now - last_report_ > kResendAfter &&
                      now - last_resend_ > kResendAfter;
  matches_ = matches;
  if (!rematched && !silent) return;
  last_resend_ = now;
  std::vector<cell::MotionSegment> again;
  for (const auto& seg : unacked_)
    if (seg.seq() > received_seq_) again.push_back(seg);
  if (again.empty()) return;
  spdlog::warn("axis servo of {} {}: re-sending seq {}..{} of run {}", station_,
               rematched ? "matched again" : "reported nothing for 1 s", again.front().seq(),
               again.back().seq(), run_id_);
  lk.unlock();  // never write under the lock: progress arrives on the bus thread and takes it
  for (const auto& seg : again) link_.Write(seg);
  lk.lock();
}

bool SegmentStream::OnProgress(const cell::SegmentProgress& p) {
  std::lock_guard lk(mu_);
  const bool held_changed = servo_held_ != p.feed_hold();
  servo_held_ = p.feed_hold();
  servo_part_run_ = p.part_run_id();
  // Progress from another servo process than the one this run started on: the servo restarted and the
  // segments it had are gone (it refuses to join a run in the middle).
  if (run_id_ != 0 && run_boot_ != 0 && p.boot_id() != run_boot_) servo_restarted_ = true;
  if (p.run_id() == run_id_ && run_id_ != 0) {
    if (run_boot_ == 0) run_boot_ = p.boot_id();
    completed_seq_ = std::max(completed_seq_, p.completed_seq());
    credit_seq_ = std::max(credit_seq_, p.credit_seq());
    received_seq_ = p.received_seq();
    last_report_ = last_progress_ = clock_.Now();
    while (!unacked_.empty() && unacked_.front().seq() <= completed_seq_) unacked_.pop_front();
    run_machine_s_ = p.run_machine_s();
    for (const auto& c : p.cutting()) {
      Cut& cut = cut_[{c.tool().to_string(), c.socket()}];
      cut.reported_s = std::max(cut.reported_s, c.cutting_s());
    }
    if (p.alarm()) {
      alarm_ = true;
      alarm_code_ = p.alarm_code().to_string();
      alarm_text_ = p.alarm_text().to_string();
    }
  }
  cv_.notify_all();
  return held_changed;
}

void SegmentStream::OnProbe(const cell::ProbeResult& r) {
  std::lock_guard lk(mu_);
  if (r.run_id() != run_id_ || r.seq() == 0 || r.seq() > sent_seq_) return;
  probes_[r.seq()] = r;
  cv_.notify_all();
}

void SegmentStream::Wake() {
  std::lock_guard lk(mu_);
  cv_.notify_all();
}

std::vector<tooltable::ToolWear> SegmentStream::TakeWear() {
  std::lock_guard lk(mu_);
  std::vector<tooltable::ToolWear> out;
  for (auto& [key, cut] : cut_) {
    if (cut.reported_s <= cut.taken_s) continue;
    out.push_back(tooltable::ToolWear{key.first, key.second, cut.reported_s - cut.taken_s, false});
    cut.taken_s = cut.reported_s;
  }
  return out;
}

double SegmentStream::RunMachineSeconds() const {
  std::lock_guard lk(mu_);
  return run_machine_s_;
}

bool SegmentStream::ServoHeld() const {
  std::lock_guard lk(mu_);
  return servo_held_;
}

std::uint64_t SegmentStream::SentSeq() const {
  std::lock_guard lk(mu_);
  return sent_seq_;
}

std::size_t SegmentStream::Unacknowledged() const {
  std::lock_guard lk(mu_);
  return unacked_.size();
}

}  // namespace cell::station
