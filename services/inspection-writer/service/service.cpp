#include "cell/inspection/service.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <ctime>
#include <string>

#include "cell/bus/topics.h"
#include "cell/health/health.h"
#include "cell/records/entries.h"
#include "cell/records/page.h"
#include "cell/records/time.h"

namespace cell::inspection {

namespace {

// The last lines of a file, up to `n` bytes, starting at a line.
std::string Tail(const std::string& text, size_t n) {
  if (text.size() <= n) return text;
  size_t from = text.find('\n', text.size() - n);
  return from == std::string::npos ? text.substr(text.size() - n) : text.substr(from + 1);
}

// A station's interpreter stores its own run records and files, and files it sends HOST (KT-APL RCP TO
// HOST); nothing of another station (docs/security.md: the writer checks the sender's identity).
void CheckRequester(const cell::InspectionRequest& r) {
  const std::string& who = bus::RequesterIdentity();
  const std::string own = bus::StationOfIdentity(who);
  if (own.empty()) return;
  std::string of;
  const std::string run = r.run().station().to_string(), file = r.file().station().to_string();
  if (r.op() == cell::INSPECTION_STORE_RUN && !bus::StationOwns(own, run)) of = run;
  if (r.op() == cell::INSPECTION_STORE_FILE && !bus::StationOwns(own, file) && file != "HOST") of = file;
  if (!of.empty())
    throw Error(Errc::kPermissionDenied,
                fmt::format("identity '{}' may store records of station {} only, not of {}", who, own, of));
}

// The audit trail: what a request stores; empty for a query.
std::string Describe(const cell::InspectionRequest& r) {
  if (r.op() == cell::INSPECTION_STORE_RUN)
    return fmt::format("run record of {} dispatch {}", r.run().station().to_string(), r.run().dispatch_id());
  if (r.op() == cell::INSPECTION_STORE_FILE)
    return fmt::format("file {}/{}", r.file().station().to_string(), r.file().file().to_string());
  return {};
}

}  // namespace

Service::Service(bus::Participant& p, Records& records)
    : records_(records),
      stored_(p, bus::topics::kInspectionStored, bus::QosKind::kEvent),
      server_(
          p, bus::topics::kInspection, [this](const cell::InspectionRequest& r) { return Handle(r); },
          Describe) {}

cell::InspectionReply Service::Handle(const cell::InspectionRequest& r) {
  CheckRequester(r);
  cell::InspectionReply rep;
  cell::InspectionStored ev;  // published once the record is durable
  switch (r.op()) {
    case cell::INSPECTION_STORE_RUN: {
      const auto& x = r.run();
      nlohmann::json programs = nlohmann::json::array();
      for (auto& p : x.programs()) programs.push_back(p.to_string());
      nlohmann::json j = {{"station", x.station().to_string()},
                          {"dispatch_id", x.dispatch_id()},
                          {"job_id", x.job_id()},
                          {"pallet", x.pallet()},
                          {"programs", programs},
                          {"completed", x.completed()},
                          {"reason", x.reason().to_string()},
                          {"started", records::IsoTime(x.started_ns())},
                          {"finished", records::IsoTime(x.finished_ns())},
                          {"machine_s", x.machine_s()}};
      std::string name = records_.StoreRun(j);
      spdlog::info("stored {}", name);
      rep.info(name);
      ev.kind(cell::STORED_RUN);
      ev.name(name);
      ev.station(x.station());
      ev.run(x);
      break;
    }
    case cell::INSPECTION_STORE_FILE:
      rep.info(records_.StoreFile(r.file().station().to_string(), r.file().file().to_string(),
                                  r.file().text().to_string()));
      ev.kind(cell::STORED_FILE);
      ev.name(rep.info().to_string());
      ev.station(r.file().station());
      ev.excerpt(Tail(r.file().text().to_string(), 4000));
      ev.text(r.file().text());  // the whole file, for viewers (docs/security.md)
      break;
    case cell::INSPECTION_LIST: {  // one page by name within the reply's bound; file.station filters
      records::PageBuilder page(r.page().limit());
      const std::string station = r.file().station().to_string();
      records_.List(r.name().to_string().empty() ? "*" : r.name().to_string(), r.page().after().to_string(),
                    [&](const records::InspectionEntry& e) {
                      return (!station.empty() && e.station != station) ||
                             page.Add(records::InspectionRow(e));
                    });
      rep.info(page.Text());
      rep.more(page.more());
      break;
    }
    case cell::INSPECTION_CAT: {
      auto text = records_.Cat(r.name().to_string());
      if (!text) throw Error(Errc::kNotFound, "no record or file " + r.name().to_string());
      if (text->size() > 65536) throw Error(Errc::kFailedPrecondition, "file larger than 64 KiB");
      rep.info(*text);
      break;
    }
  }
  if (!ev.name().to_string().empty()) {
    ev.time_ns(health::WallNs());
    try {
      stored_.Write(ev);
    } catch (const Error& e) {  // a notice for viewers; the record itself is stored
      spdlog::warn("{}: not announced: {}", ev.name().to_string(), e.what());
    }
  }
  return rep;
}

}  // namespace cell::inspection
