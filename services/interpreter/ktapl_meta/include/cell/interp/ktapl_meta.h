// The heading data of a KT-APL program (manual, "Proper Sequence of KT/FMS Program Heading"):
//   %                 rewind stop, required
//   (NAM,name)        optional
//   (UTL,t1,t2,...)   optional, right before UCY (DESIGN §5: tool numbers of up to 7 digits, optional T)
//   (UCY,seconds)     required in KT/FMS part programs
// ASCII (MNE,...) and EIA %MNE,...% forms, any case. One reader for the interpreter, the program store and
// the scheduler; each decides what a warning means to it (the scheduler refuses a malformed UTL or UCY).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cell::interp {

struct KtaplMetaWarning {
  enum class Kind {
    kOrder,  // where a statement stands (heading order, sequence numbers, % first); its value is still read
    kValue,  // what a statement says: malformed statement, entry or value, or a second NAM/UCY; that part
             // is left out
  };
  Kind kind = Kind::kOrder;
  std::string mnemonic;  // "NAM", "UTL", "UCY"; "" for the heading as a whole
  int line = 0;          // 1-based; 0 for the program as a whole
  int column = 0;        // 1-based column of the statement, entry or value; 0 with line 0
  std::string text;

  // "line N: text" ("text" alone for line 0).
  std::string Format() const;
};

struct KtaplMetadata {
  std::optional<std::string> name;  // the first (NAM,name), trimmed; absent when there is none or it is empty
  std::vector<std::string> tools;   // UTL tool numbers in order, T dropped, digits as written ("0012");
                                    // several UTL statements add up
  std::optional<double> cycle_s;    // the first (UCY,seconds): up to 7 digits, decimals allowed
  std::vector<KtaplMetaWarning> warnings;  // in the order found
};

struct KtaplMetaOptions {
  bool whole_seconds = false;  // a UCY with a decimal point is a kValue warning (and not read)
  bool part_program = false;   // a UTL without UCY is a warning (KT/FMS part programs need UCY)
};

// Reads NAM, UTL and UCY wherever they stand (outside ! comments and other statements' quoted text) and
// reports every departure from the heading rules as a warning. Never throws.
KtaplMetadata ExtractKtaplMetadata(std::string_view text, const KtaplMetaOptions& options = {});

}  // namespace cell::interp
