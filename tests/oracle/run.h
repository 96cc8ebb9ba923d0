// The command line's shared helpers: files, the shell, the per-program seeds (main.cpp, props.cpp).
#pragma once

#include <sys/wait.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace cell::oracle {

inline std::string Slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void Spit(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

inline std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

inline int Shell(const std::string& cmd) {
  int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128;
}

// A seed per program: the run's seed, the dialect and the program's index.
inline std::uint64_t ProgramSeed(std::uint64_t seed, const std::string& dialect, int index) {
  std::uint64_t h = seed * 0x100000001B3ull;
  for (char c : dialect) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001B3ull;
  // Mixed (murmur's finaliser): seeds a fixed step apart would give the generator's splitmix sequence
  // shifted.
  std::uint64_t z = h ^ (static_cast<std::uint64_t>(index) * 0xD6E8FEB86659FD93ull);
  z = (z ^ (z >> 33)) * 0xFF51AFD7ED558CCDull;
  z = (z ^ (z >> 33)) * 0xC4CEB9FE1A85EC53ull;
  return z ^ (z >> 33);
}

// What a property check that writes its own programs runs with (props.cpp parses it): one program per ten
// blocks of `blocks`.
struct PropRun {
  std::string interp, keep;
  std::uint64_t seed = 1;
  int blocks = 1000;
  bool plant = false;  // the check's planted error: it must fail
};
// `prop --property nogouge` (nogouge.cpp): no gouge under cutter radius compensation, Balt-System and KT-APL.
// Returns the number of contours that break it.
int NoGouge(const PropRun& o, const std::string& dialect, const std::filesystem::path& dir);
// `prop --property corners` (corners.cpp): chamfer and radius insertion stays inside the corner. Returns the
// number of corners that break it.
int Corners(const PropRun& o, const std::string& dialect, const std::filesystem::path& dir);
// `prop --property rapids` (rapids.cpp): a cycle's rapids never enter the stock it cuts. Returns the number
// of cycles that break it.
int Rapids(const PropRun& o, const std::string& dialect, const std::filesystem::path& dir);

// `check --comp` (comp.cpp): the LinuxCNC differential under cutter radius compensation, Balt-System and
// KT-APL, and tool-nose radius compensation, EMCO and Okuma: random compensated contours (turned profiles)
// until `o.blocks` contour blocks; the first `show` findings printed.
struct CompTally {
  int programs = 0, blocks = 0, agreeing = 0, disagreeing = 0, rs274_refused = 0, cell_refused = 0, shown = 0;
  int bent = 0;        // corners at a small turn whose point is not compared (comp.cpp)
  int cell_alarm = 0;  // the lathes: refused by cell-interp with the manual's alarm for that path (comp.cpp)
  long moves = 0;      // moves compared
  int bypassed = 0;    // KT-APL's programs under G46 (comp.cpp)
};
CompTally CompCheck(const PropRun& o, const std::string& rs274, const std::string& dialect,
                    const std::filesystem::path& dir, int show);

// `cell-oracle-gen prop`: the properties every program keeps (props.cpp).
int Properties(int argc, char** argv);
// `cell-oracle-gen parts`: one part in every dialect of its kind (parts_cli.cpp).
int Parts(int argc, char** argv);

}  // namespace cell::oracle
