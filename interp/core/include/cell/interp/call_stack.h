// The subprogram call stack of a run and the block stepping over it: each frame reads a span of program text
// line by line (the main program, a subprogram, subroutine or cycle body), remembers where labels were
// found, and the main program gives back the pages of a mapped text it has passed.
//
// `Data` is what a dialect keeps per frame besides the text position (its local variables, repeat counts,
// whether the frame is a cycle, ...).
#pragma once

#include <cstddef>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cell/interp/program_text.h"

namespace cell::interp {

// A place in a program text: byte offset and 1-based line number.
struct TextPos {
  std::size_t pos = 0;
  int line = 1;
};

// A range of program text a frame executes.
struct TextSpan {
  std::shared_ptr<const ProgramText> text;
  std::size_t begin = 0, end = 0;
  int begin_line = 1;
  // A lone '\r' ends a line too (tapes whose end of block is CR, as Okuma's EIA code; "\r\n" is one end).
  bool cr_ends_line = false;
};

// One line of program text (without its '\n'; a trailing '\r' is left to the dialect unless the span's
// cr_ends_line).
struct Line {
  std::string_view text;
  int number = 1;
  std::size_t start = 0;
};

// Reads the line at `at` within `span` and advances `at` past it. Precondition: at.pos < span.end.
Line ReadLine(const TextSpan& span, TextPos& at);

// Recently used jump targets of a frame (most recent first, at most kSize), so a loop finds its label
// without scanning the text again.
template <class Key, std::size_t kSize = 10>
class JumpTargets {
 public:
  std::optional<TextPos> Find(const Key& key) {
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->first == key) {
        auto entry = *it;
        entries_.erase(it);
        entries_.insert(entries_.begin(), entry);
        return entry.second;
      }
    }
    return std::nullopt;
  }
  void Remember(const Key& key, TextPos at) {
    entries_.insert(entries_.begin(), {key, at});
    if (entries_.size() > kSize) entries_.pop_back();
  }

 private:
  // A vector: a deque allocates when constructed, and a frame is constructed at every call.
  std::vector<std::pair<Key, TextPos>> entries_;
};

template <class Data>
struct Frame {
  TextSpan span;
  TextPos at;              // the next line to read
  std::string name;        // subprogram / cycle name ("" for the main program)
  bool report_own = true;  // commands and errors carry this frame's lines (else the calling block's)
  int call_line = 0;       // the line reported while report_own is false
  bool jumped = false;     // a jump ran in this frame: its blocks may run again (parse cache)
  Data data{};
};

template <class Data>
class CallStack {
 public:
  using FrameT = Frame<Data>;

  // The main program: the whole text.
  explicit CallStack(std::shared_ptr<const ProgramText> main) {
    FrameT f;
    f.span.end = main->view().size();
    f.span.text = std::move(main);
    frames_.push_back(std::move(f));
  }

  std::size_t depth() const { return frames_.size(); }  // 1 = only the main program
  FrameT& top() { return frames_.back(); }
  const FrameT& top() const { return frames_.back(); }
  FrameT& operator[](std::size_t i) { return frames_[i]; }
  const FrameT& operator[](std::size_t i) const { return frames_[i]; }
  auto begin() { return frames_.begin(); }
  auto end() { return frames_.end(); }
  auto begin() const { return frames_.begin(); }
  auto end() const { return frames_.end(); }

  // A frame over `span`, starting at its beginning.
  FrameT& Push(TextSpan span, std::string name) {
    FrameT f;
    f.at = {span.begin, span.begin_line};
    f.span = std::move(span);
    f.name = std::move(name);
    frames_.push_back(std::move(f));
    return frames_.back();
  }
  void Pop() { frames_.pop_back(); }

  // The next line of the top frame, or nullopt at its end. The main program runs forward: every MiB it has
  // passed is given back (a mapped file faults back in if a jump or a call returns there).
  std::optional<Line> NextLine() {
    FrameT& f = frames_.back();
    if (f.at.pos >= f.span.end) return std::nullopt;
    Line l = ReadLine(f.span, f.at);
    if (frames_.size() == 1) released_.At(*f.span.text, f.at.pos);
    return l;
  }

 private:
  std::vector<FrameT> frames_;
  ReleaseBehind released_;
};

inline Line ReadLine(const TextSpan& span, TextPos& at) {
  std::string_view text = span.text->view();
  // Two memchr scans, not find_first_of: libstdc++ runs find_first_of as one search of the needle per
  // character of the text, which made line splitting the interpreter's hottest path.
  std::size_t nl = text.find('\n', at.pos);
  if (span.cr_ends_line) {
    const std::size_t stop = nl == std::string_view::npos ? text.size() : nl;
    if (const void* cr = std::memchr(text.data() + at.pos, '\r', stop - at.pos))
      nl = static_cast<std::size_t>(static_cast<const char*>(cr) - text.data());
  }
  if (nl == std::string_view::npos || nl > span.end) nl = span.end;
  Line l{std::string_view(text.data() + at.pos, nl - at.pos), at.line, at.pos};
  std::size_t next = nl + 1;
  if (span.cr_ends_line && nl < span.end && text[nl] == '\r' && next < span.end && text[next] == '\n') ++next;
  at.pos = nl < span.end ? next : span.end;
  ++at.line;
  return l;
}

}  // namespace cell::interp
