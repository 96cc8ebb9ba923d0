// The station's discrete I/O (docs/station.md, "Discrete I/O"): named inputs and outputs, each 0 or 1,
// persisted in StationDb and published on every change.
//
// Names: a KT-APL bit is its word address and bit number, "O83D.0", "I04D.1" (manual ln 3948-3973: 16-bit
// words, bits 0-15); an Okuma I/O variable is written as the program writes it, "VDOUT[5]"; the station
// file's [[io.aux]] outputs are named there ("CHUCK"). Inputs are the operator's (`cellctl station input`,
// KT-APL form only); outputs are the programs'.
//
// The parsers turn the dialects' OutputOp / WaitInputOp specs into bits; AuxIo applies the station file's
// M-code map with its spindle interlocks for one program.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/config/config.h"
#include "cell/interp/canon.h"
#include "cell/station/station_db.h"

namespace cell::station {

// One point and its value (an output to set, an input state to wait for).
struct IoBit {
  std::string name;
  int value = 0;
  bool operator==(const IoBit&) const = default;
};

// What an OutputOp asks: bits to set, or (KT-APL `(SET)` without arguments) the outputs saved as the
// power-up default.
struct OutputSpec {
  bool save = false;
  std::vector<IoBit> bits;
};

// True for a KT-APL bit name of `kind` 'I' or 'O': the letter, 1-4 hexadecimal digits, '.', bit 0-15.
bool IsWordBitName(std::string_view name, char kind);

// KT-APL `(SET,O83D,0=1,O83E,3=0)` (spec "O83D,0=1,O83E,3=0", "SAVE" for `(SET)`) and Okuma
// "VDOUT[n]=v". nullopt for another dialect's form (the station does not execute it); throws
// cell::Error(kInvalidArgument) for a malformed one (a value other than 0/1, a bit past 15).
std::optional<OutputSpec> ParseOutputSpec(const std::string& spec);
// KT-APL `(WAI,I04D,1=1,I03D,3=0)`: the states to wait for. nullopt for another dialect's form (EMCO M65);
// throws cell::Error(kInvalidArgument) for a malformed one.
std::optional<std::vector<IoBit>> ParseWaitSpec(const std::string& spec);
// "I04D.1=1 I03D.3=0"
std::string Describe(const std::vector<IoBit>& bits);

struct IoState {
  std::map<std::string, int> inputs;
  std::map<std::string, int> outputs;
  std::map<std::string, int> power_up;  // saved output states (absent: 0, the deadload default)
  std::uint32_t revision = 0;
};

class DiscreteIo {
 public:
  // Loads the stored I/O; the station file's aux outputs are listed (at 0) until a program sets them.
  // `publish` is called after every change under the I/O's lock (publications never overtake each other).
  DiscreteIo(StationDb& db, const std::vector<config::AuxOutput>& aux,
             std::function<void(const IoState&)> publish);

  IoState Get() const;
  void Announce() const;
  // The operator's inputs (`cellctl station input`): KT-APL bit names, 0 or 1; throws
  // cell::Error(kInvalidArgument) and sets nothing when one is refused. Returns the new revision.
  std::uint32_t SetInputs(const std::vector<IoBit>& bits);
  // A program's outputs; throws cell::Error(kInvalidArgument) for a name or value outside the model.
  void SetOutputs(const std::vector<IoBit>& bits);
  // KT-APL `(SET)`: the outputs as they stand become the power-up default (manual ln 3962-3963).
  void SavePowerUp();
  // True when every bit is in the stated state (an input never set is 0).
  bool Satisfied(const std::vector<IoBit>& condition) const;

 private:
  void Changed();  // caller holds mu_

  StationDb& db_;
  std::function<void(const IoState&)> publish_;
  mutable std::mutex mu_;
  IoState now_;
};

// The station file's M-code map for one program: which M codes set which output, and the interlocks
// "not while the spindle rotates" that other M codes switch off and on (ON at the program's start: the
// control's reset state, Okuma manual ln 2013, 2020).
class AuxIo {
 public:
  explicit AuxIo(const std::vector<config::AuxOutput>& map) : map_(map), interlocked_(map.size(), true) {}
  // Follows the spindle: rotating after M03/M04 with a speed, stopped after M05 or an orientation.
  void Spindle(const interp::SpindleOp& s);
  // The output an M code sets; nullopt when the map does not name it (or it switches an interlock).
  // Throws cell::Error(kFailedPrecondition) for an interlocked M code while the spindle rotates.
  std::optional<IoBit> Aux(int m);
  bool SpindleRotates() const { return rotating_; }

 private:
  const std::vector<config::AuxOutput>& map_;
  std::vector<bool> interlocked_;  // per entry: its interlock is ON
  bool rotating_ = false;
};

}  // namespace cell::station
