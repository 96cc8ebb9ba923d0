// The text of a part program as the interpreter reads it: an owned string, or a read-only mapping of a
// file. A mapped program is paged in as the run reaches it and the pages the run has passed are given
// back (Release), so resident memory does not grow with program length; a GTO or a subroutine call back
// into released text faults it in again from the page cache.
#pragma once

#include <memory>
#include <string>
#include <string_view>

namespace cell::interp {

class ProgramText {
 public:
  static std::shared_ptr<const ProgramText> FromString(std::string text);
  // Throws cell::Error(kNotFound / kInvalidArgument) when the file cannot be opened or mapped. An empty
  // file is held as an empty string (mmap refuses length 0).
  static std::shared_ptr<const ProgramText> MapFile(const std::string& path);

  ProgramText(const ProgramText&) = delete;
  ProgramText& operator=(const ProgramText&) = delete;
  ~ProgramText();

  std::string_view view() const { return view_; }
  // Advice that bytes [from, to) are unlikely to be read soon: a mapping drops the whole pages inside
  // that range from the process (the data stays valid). No effect on an owned string.
  void Release(size_t from, size_t to) const;

 private:
  ProgramText() = default;
  std::string owned_;
  void* map_ = nullptr;
  size_t map_len_ = 0;
  std::string_view view_;
};

// Gives back the pages a forward pass over a text has read, a step (1 MiB) at a time, so resident memory
// stays flat however long a mapped program is (a later jump back faults them in again). One rule for the
// run itself (CallStack) and for the dialects' scans for a program or a sequence name.
class ReleaseBehind {
 public:
  static constexpr std::size_t kStep = std::size_t{1} << 20;
  explicit ReleaseBehind(std::size_t from = 0) : start_(from), released_(from) {}
  // The pass has reached `pos`.
  void At(const ProgramText& text, std::size_t pos) {
    if (pos - released_ < kStep) return;
    text.Release(released_, pos);
    released_ = pos;
  }
  // The pass ended at `pos`: what is left behind goes back too when the pass was a long one.
  void Done(const ProgramText& text, std::size_t pos) {
    if (pos - start_ >= kStep && pos > released_) text.Release(released_, pos);
  }

 private:
  std::size_t start_;
  std::size_t released_;
};

}  // namespace cell::interp
