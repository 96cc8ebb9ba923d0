// cell-dnc's bus binding (docs/dnc.md "On the bus").
#include "cell/dnc/service.h"

#include <termios.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>

#include "cell/bus/topics.h"
#include "cell/dnc/client.h"
#include "cell/health/health.h"

namespace cell::dnc {
namespace {

nlohmann::json Figures(const Stats& st) {
  return {{"bytes", st.bytes},
          {"seconds", st.seconds},
          {"rate", st.Rate()},
          {"stalls", st.stalls},
          {"stopped_s", st.stalled_s}};
}

cell::DncReply Reply(const std::string& station, const nlohmann::json& info, uint32_t revision = 0) {
  cell::DncReply rep;
  rep.station(station);
  rep.revision(revision);
  rep.info(info.dump());
  return rep;
}

// A tty's input is emptied before a receive: a flow-control byte left from an earlier send is no program.
void FlushInput(Port& port) {
  if (auto* tty = dynamic_cast<TtyPort*>(&port)) tcflush(tty->fd(), TCIFLUSH);
}

}  // namespace

Service::Service(bus::Participant& p, std::string station, std::string dialect, Serial serial,
                 std::unique_ptr<Port> line, Opener reopen)
    : station_(std::move(station)),
      dialect_(std::move(dialect)),
      serial_(std::move(serial)),
      open_(std::move(reopen)),
      port_(std::move(line)),
      store_(p),
      status_w_(p, bus::topics::kDncStatus, bus::QosKind::kState),
      server_(
          p, bus::topics::StationDnc(station_), [this](const cell::DncRequest& r) { return Handle(r); },
          [](const cell::DncRequest& r) {
            // A READ is asked after every 200 ms while it waits: the run's READ and WRITE are its station's
            // own (logged by cell-dnc as they end), not the operator's requests.
            if (r.op() == cell::DNC_STATUS || r.op() == cell::DNC_READ || r.op() == cell::DNC_WRITE)
              return std::string();
            return fmt::format("dnc {} {} {}:{}", OpName(r.op()), r.station().to_string(),
                               r.node().to_string(), r.name().to_string());
          }) {
  status_.station(station_);
  status_.device(serial_.device);
  status_.state(cell::DNC_IDLE);
  std::lock_guard lk(mu_);
  Publish();
}

Service::~Service() {
  cancel_ = true;  // the transfer under way (on the bus's thread) ends now, so the server can go
  std::unique_ptr<ReadTask> t;
  {
    std::lock_guard lk(task_mu_);
    t = std::move(task_);
  }
  Abandon(std::move(t));
}

Port& Service::Line() {
  if (!port_) port_ = open_();
  return *port_;
}

cell::DncReply Service::Handle(const cell::DncRequest& r) {
  if (r.station().to_string() != station_)
    throw Error(Errc::kInvalidArgument,
                fmt::format("this is the DNC line of station {}, not {}", station_, r.station().to_string()));
  switch (r.op()) {
    case cell::DNC_SEND:
      return Send(r, false);
    case cell::DNC_DRIP:
      return Send(r, true);
    case cell::DNC_RECEIVE:
      return Receive(r);
    case cell::DNC_STATUS:
      return Status();
    case cell::DNC_READ:
      return Read(r);
    case cell::DNC_WRITE:
      return Write(r);
  }
  throw Error(Errc::kInvalidArgument, fmt::format("unknown DNC operation {}", static_cast<int>(r.op())));
}

// The bytes out on the line, paced by its rate and flow control, after Begin(): the transfer's End() either
// way (SEND/DRIP with progress samples, a WRITE's short record without).
Stats Service::SendPaced(const std::vector<uint8_t>& bytes, decltype(SendOptions::stall_timeout) stall,
                         bool progress) {
  SendOptions o;
  o.flow = serial_.flow;
  o.bytes_per_s = LineRate(serial_);
  o.stall_timeout = stall;
  if (progress) o.progress = [this](const Stats& st) { Progress(st); };
  o.cancel = &cancel_;
  Stats st;
  try {
    st = dnc::Send(Line(), bytes, o);
  } catch (const Error& e) {
    End(st, e.what());
    throw;
  }
  End(st, "");
  return st;
}

cell::DncReply Service::Send(const cell::DncRequest& r, bool drip) {
  const std::string name = r.name().to_string();
  const std::string node = r.node().to_string();
  auto file = node.empty() ? store_.FetchWithFallback(station_, name) : store_.Fetch(node, name);
  if (!file) {
    throw Error(Errc::kNotFound, node.empty() ? fmt::format("no program '{}' in {} or HOST", name, station_)
                                              : fmt::format("no program '{}' in {}", name, node));
  }
  const std::string where = fmt::format("{}:{}", file->info.value("node", node), name);
  CheckNotHeld(drip ? "dnc drip" : "dnc send");
  if (!drip) CheckMemory(where, file->content.size());
  std::vector<uint8_t> bytes;
  try {
    bytes = Encode(serial_.format, file->content);
  } catch (const Error& e) {
    throw Error(e.code(), fmt::format("{}: {}", where, e.what()));
  }
  Begin(drip ? cell::DNC_DRIPPING : cell::DNC_SENDING, where, bytes.size());
  const Stats st = SendPaced(bytes, drip ? kDripStall : kSendStall, true);
  spdlog::info("{} {}: {} bytes in {:.1f} s, {} stops", drip ? "dripped" : "sent", where, st.bytes,
               st.seconds, st.stalls);
  nlohmann::json info = Figures(st);
  info["program"] = where;
  return Reply(station_, info);
}

// A program longer than the control's memory is refused before a byte goes out (MemoryRefusal); a drip feed
// is for such programs.
void Service::CheckMemory(const std::string& where, size_t characters) const {
  const std::string why = MemoryRefusal(serial_, characters);
  if (why.empty()) return;
  throw Error(Errc::kFailedPrecondition, fmt::format("{}: {}: feed it with `cellctl dnc drip {} {}`", where,
                                                     why, station_, where.substr(where.find(':') + 1)));
}

cell::DncReply Service::Receive(const cell::DncRequest& r) {
  const std::string name = r.name().to_string();
  const std::string node = r.node().size() == 0 ? station_ : r.node().to_string();
  const std::string where = fmt::format("{}:{}", node, name);
  CheckNotHeld("dnc receive");
  ReceiveOptions o;
  o.flow = serial_.flow;
  o.progress = [this](const Stats& st) { Progress(st); };
  o.cancel = &cancel_;
  Received got;
  try {
    FlushInput(Line());  // before the line says it is receiving: what comes after that is the program
    Begin(cell::DNC_RECEIVING, where);
    got = dnc::Receive(Line(), serial_.format, o);
    if (got.text.find_first_not_of("\n") == std::string::npos)
      throw Error(Errc::kInvalidArgument, fmt::format("device {}: byte {}: no program between the leader and "
                                                      "the end of data",
                                                      serial_.device, got.stats.bytes));
  } catch (const Error& e) {
    End(got.stats, e.what());
    throw Error(e.code(), fmt::format("{}; nothing stored", e.what()));
  }
  // Complete and checked: only now does it become a revision (a new one when the name exists).
  program_store::Client::PutOptions put;
  put.node = node;
  put.force = true;
  put.dialect = dialect_;
  nlohmann::json stored;
  try {
    stored = store_.Put(name, got.text, put);
  } catch (const Error& e) {
    End(got.stats, e.what());
    throw Error(e.code(), fmt::format("received {} bytes, not stored: {}", got.stats.bytes, e.what()));
  }
  End(got.stats, "");
  const uint32_t revision = stored.value("revision", 0u);
  spdlog::info("received {} revision {}: {} bytes in {:.1f} s", where, revision, got.stats.bytes,
               got.stats.seconds);
  nlohmann::json info = Figures(got.stats);
  info["program"] = where;
  info["revision"] = revision;
  info["size"] = got.text.size();
  return Reply(station_, info, revision);
}

void Service::CheckNotHeld(std::string_view what) {
  std::lock_guard lk(task_mu_);
  if (!task_) return;
  throw Error(Errc::kFailedPrecondition,
              fmt::format("device {}: held by station {}'s program ({}, READ waiting for a record): {} is "
                          "refused until that READ ends",
                          serial_.device, station_, task_->holder, what));
}

void Service::Abandon(std::unique_ptr<ReadTask> t) {
  if (!t) return;
  t->cancel = true;
  if (t->thread.joinable()) t->thread.join();
}

// The READ waits on its own thread, so that the line's other requests are answered meanwhile: a transfer
// is refused while it holds the line, and a stop of the program (the station no longer asking) ends it.
cell::DncReply Service::Read(const cell::DncRequest& r) {
  const std::string holder = r.name().to_string();
  std::unique_lock lk(task_mu_);
  if (task_ && task_->holder != holder) {  // an earlier run's READ, left when that run ended
    auto old = std::move(task_);
    lk.unlock();
    Abandon(std::move(old));
    lk.lock();
  }
  if (!task_) {
    if (const std::string why = RecordRefusal(serial_.format); !why.empty())
      throw Error(Errc::kFailedPrecondition, fmt::format("device {}: {}", serial_.device, why));
    task_ = std::make_unique<ReadTask>();
    task_->holder = holder;
    task_->asked = std::chrono::steady_clock::now();
    task_->thread = std::thread([this, t = task_.get()] { ReadLoop(*t); });
    return Reply(station_, {{"done", false}});
  }
  task_->asked = std::chrono::steady_clock::now();
  if (!task_->done) return Reply(station_, {{"done", false}});
  auto t = std::move(task_);
  lk.unlock();
  t->thread.join();
  if (!t->error.empty()) throw Error(Errc::kUnavailable, t->error);
  cell::DncReply rep = Reply(station_, {{"done", true}, {"characters", t->record.size()}});
  rep.data(std::vector<uint8_t>(t->record.begin(), t->record.end()));
  return rep;
}

void Service::ReadLoop(ReadTask& t) {
  Stats st;
  try {
    Begin(cell::DNC_READING, t.holder);
    RecordOptions o;
    o.cancel = &t.cancel;
    t.record = ReadRecord(Line(), serial_.format, o);
    st.bytes = t.record.size() + 1;
    End(st, "");
    spdlog::info("READ of {}: {} characters", t.holder, t.record.size());
  } catch (const Error& e) {
    if (t.cancel) {
      End(st, "");  // the program stopped: no fault of the line
      spdlog::info("READ of {} ended: its run no longer waits", t.holder);
    } else {
      t.error = e.what();
      End(st, t.error);
    }
  }
  t.done = true;
}

cell::DncReply Service::Write(const cell::DncRequest& r) {
  const std::string holder = r.name().to_string();
  {
    std::unique_lock lk(task_mu_);
    if (task_ && task_->holder == holder && !task_->done)
      throw Error(Errc::kFailedPrecondition,
                  fmt::format("device {}: a READ of {} is waiting on the line", serial_.device, holder));
    if (task_ && task_->holder != holder) {
      auto old = std::move(task_);
      lk.unlock();
      Abandon(std::move(old));
    }
  }
  const std::string record(r.data().begin(), r.data().end());
  std::vector<uint8_t> bytes;
  try {
    bytes = EncodeRecord(serial_.format, record);
  } catch (const Error& e) {
    throw Error(e.code(), fmt::format("device {}: {}", serial_.device, e.what()));
  }
  Begin(cell::DNC_WRITING, holder, bytes.size());
  const Stats st = SendPaced(bytes, kSendStall, false);
  spdlog::info("WRITE of {}: {} characters", holder, record.size());
  return Reply(station_, Figures(st));
}

cell::DncReply Service::Status() {
  std::lock_guard lk(mu_);
  return Reply(station_, StatusJson(status_));
}

void Service::Begin(cell::DncState state, const std::string& program, uint64_t total) {
  std::lock_guard lk(mu_);
  status_.state(state);
  status_.program(program.substr(0, 160));
  status_.total(total);
  status_.failed(false);
  status_.bytes(0);
  status_.seconds(0);
  status_.rate(0);
  status_.stalls(0);
  status_.stopped_s(0);
  Publish();
}

void Service::Progress(const Stats& st, bool force) {
  std::lock_guard lk(mu_);
  status_.bytes(st.bytes);
  status_.seconds(st.seconds);
  status_.rate(st.Rate());
  status_.stalls(static_cast<uint32_t>(st.stalls));
  status_.stopped_s(st.stalled_s);
  dirty_ = true;
  if (force || std::chrono::steady_clock::now() - published_ > std::chrono::milliseconds(500)) Publish();
}

void Service::Tick() {
  std::unique_ptr<ReadTask> gone;
  {
    std::lock_guard lk(task_mu_);
    if (task_ && std::chrono::steady_clock::now() - task_->asked > kReadLease) gone = std::move(task_);
  }
  Abandon(std::move(gone));
  std::lock_guard lk(mu_);
  if (dirty_) Publish();
}

void Service::End(const Stats& st, const std::string& error) {
  if (error.empty()) Progress(st);  // a failed transfer keeps its last figures (Send's are lost in the throw)
  std::lock_guard lk(mu_);
  status_.state(cell::DNC_IDLE);
  status_.transfers(status_.transfers() + 1);
  status_.failed(!error.empty());
  if (!error.empty()) {
    status_.errors(status_.errors() + 1);
    status_.last_error(error.substr(0, 512));
    port_.reset();  // opened again for the next transfer: a hung-up tty stays hung up
    try {
      port_ = open_();
    } catch (const Error& e) {
      spdlog::error("{}", e.what());  // the next transfer tries again, and says why it cannot
    }
  }
  Publish();
}

void Service::Publish() {
  dirty_ = false;
  status_.updated_ns(health::WallNs());
  published_ = std::chrono::steady_clock::now();
  try {
    status_w_.Write(status_);
  } catch (const Error& e) {
    spdlog::warn("cell/dnc/status: {}", e.what());
  }
}

}  // namespace cell::dnc
