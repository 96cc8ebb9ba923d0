// The processes of a local cell (`cellctl up`, `restart`, `down`): how each is started, the record in
// $CELL_DATA_DIR/cell-up.json, and whether a recorded PID is still the process that was started.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cell/proc/proc.h"

namespace cellctl {

// One entry of cell-up.json: {service, unit, pid, log, argv, env, exe, start_time}. DESIGN §6 promises
// {service, unit, pid, log}; the rest lets `restart` and `up` start a process again exactly as it was
// started, and `down` check that a PID is still that process.
struct CellProcess {
  std::string service;  // the id it announces: "cell-scheduler", "cell-interpreter/KT01"
  std::string unit;     // "cell-interpreter@KT01.service"
  pid_t pid = 0;
  std::string log;
  std::vector<std::string> argv;  // as started: argv[0] an absolute path
  std::vector<std::string> env;   // "NAME=value", the whole environment it was started with
  std::string exe;                // canonical argv[0]
  std::uint64_t start_time = 0;   // /proc/PID/stat field 22 (clock ticks after boot), read right after fork
};

nlohmann::json ToJson(const CellProcess& p);
CellProcess FromJson(const nlohmann::json& j);

// $CELL_DATA_DIR/cell-up.json.
std::filesystem::path RecordFile();
// The recorded processes; empty when there is no record. Exit{1} for a file that is not a process list.
std::vector<CellProcess> LoadRecord();
// Writes the record atomically (a new file, then rename), owner-only.
void SaveRecord(const std::vector<CellProcess>& procs);

// An advisory lock on the record (flock of cell-up.json.lock) for one read-modify-write.
class RecordLock {
 public:
  RecordLock();
  ~RecordLock();
  RecordLock(const RecordLock&) = delete;
  RecordLock& operator=(const RecordLock&) = delete;

 private:
  int fd_ = -1;
};

using cell::proc::StartTime;
// True while `pid` is still the process that was started: same start time and same executable (a binary
// replaced by a rebuild reads "PATH (deleted)" and still counts). kill(pid, 0) alone would also say yes for
// an unrelated process that reused the PID.
bool IsRunning(const CellProcess& p);

// The first cell service (cell-scheduler, cell-program-store, cell-interpreter, cell-axis-servo,
// cell-inspection-writer, cell-dashboard) that runs on this host on `domain` (its CELL_DOMAIN, 101 without
// one), or may (its environment is not ours to read), named as "cell-scheduler (pid 4711)"; nullopt when
// there is none. cellctl concludes "the cell is down" from an empty domain only when there is none: discovery
// can take a second, the process table cannot.
std::optional<std::string> LocalServiceOn(int domain);

// The environment of this process as "NAME=value" strings.
std::vector<std::string> CurrentEnvironment();

// Forks and execs p.argv with p.env (and `extra_env`, which the record does not keep), stdout and stderr
// appended to p.log, stdin /dev/null, its own session, umask 077, and no descriptor of ours beyond 0-2
// (cellctl must hold no DDS participant when it calls this). Sets p.pid, p.exe and p.start_time.
void Launch(CellProcess& p, const std::vector<std::string>& extra_env = {});

// The supervisor's end of sd_notify for a process this cellctl starts (`restart` of a station's service): its
// READY=1 (every service sends it once it serves, docs/operations.md §6.3) says it is up without this cellctl
// meeting the whole cell on the bus, which on Fast DDS at 32 stations on a loaded host took over a minute
// (§9.6). An abstract unix socket: nothing in the file system, gone with this process.
class ReadyListener {
 public:
  ReadyListener();  // Exit{1} when the socket cannot be made
  ~ReadyListener();
  ReadyListener(const ReadyListener&) = delete;
  ReadyListener& operator=(const ReadyListener&) = delete;
  // What the child's environment gains: NOTIFY_SOCKET=@<this socket>, and CELL_NOTIFY=ready (the service
  // sends READY=1 there and nothing after: no one listens once this cellctl has exited).
  std::vector<std::string> Env() const;
  // True once `p` (by its PID, from the kernel's credentials) has sent READY=1; false at `deadline` or once
  // it has ended.
  bool Wait(const CellProcess& p, std::chrono::steady_clock::time_point deadline);

 private:
  int fd_ = -1;
  std::string name_;  // the abstract address, without its leading NUL
};

// SIGTERM to every process that is still ours, SIGKILL after `grace` to those still running. Returns one line
// per recorded PID that was not ours any more (left alone).
std::vector<std::string> Stop(const std::vector<CellProcess>& procs, std::chrono::seconds grace);

// The last non-empty line of a log file.
std::string LastLine(const std::filesystem::path& log);

}  // namespace cellctl
