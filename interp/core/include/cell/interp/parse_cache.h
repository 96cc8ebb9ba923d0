// Parsed blocks that run more than once (subprogram and cycle bodies, loops) kept in a small direct-mapped
// table keyed by (program text, offset), so a loop parses each block once. An entry pins its text: parsed
// words may view it. The size is fixed, so memory does not grow with the program.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "cell/interp/program_text.h"

namespace cell::interp {

template <class Parsed, std::size_t kSlots = 256>
class ParseCache {
 public:
  const Parsed* Find(const ProgramText* text, std::size_t off) const {
    const Entry& e = table_[Slot(text, off)];
    return (e.valid && e.text.get() == text && e.off == off) ? &e.parsed : nullptr;
  }
  const Parsed& Put(const std::shared_ptr<const ProgramText>& text, std::size_t off, Parsed&& parsed) {
    Entry& e = table_[Slot(text.get(), off)];
    e.valid = true;
    e.text = text;
    e.off = off;
    e.parsed = std::move(parsed);
    return e.parsed;
  }

 private:
  struct Entry {
    bool valid = false;
    std::shared_ptr<const ProgramText> text;
    std::size_t off = 0;
    Parsed parsed;
  };
  static std::size_t Slot(const ProgramText* text, std::size_t off) {
    return (reinterpret_cast<std::uintptr_t>(text) / 16 + off * 2654435761u) % kSlots;
  }
  std::vector<Entry> table_ = std::vector<Entry>(kSlots);
};

}  // namespace cell::interp
