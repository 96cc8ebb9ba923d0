#include "cell/interp/program_text.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "cell/error/error.h"

namespace cell::interp {

std::shared_ptr<const ProgramText> ProgramText::FromString(std::string text) {
  std::shared_ptr<ProgramText> t(new ProgramText);
  t->owned_ = std::move(text);
  t->view_ = t->owned_;
  return t;
}

std::shared_ptr<const ProgramText> ProgramText::MapFile(const std::string& path) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(Errc::kNotFound, "cannot read " + path + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw Error(Errc::kInvalidArgument, "cannot read " + path + ": not a regular file");
  }
  std::shared_ptr<ProgramText> t(new ProgramText);
  if (st.st_size > 0) {
    auto len = static_cast<size_t>(st.st_size);
    void* p = ::mmap(nullptr, len, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      int e = errno;
      ::close(fd);
      throw Error(Errc::kInvalidArgument, "cannot map " + path + ": " + std::strerror(e));
    }
    ::madvise(p, len, MADV_SEQUENTIAL);  // read-ahead for the straight run through the main program
    t->map_ = p;
    t->map_len_ = len;
    t->view_ = std::string_view(static_cast<const char*>(p), len);
  }
  ::close(fd);  // the mapping keeps the file
  return t;
}

ProgramText::~ProgramText() {
  if (map_) ::munmap(map_, map_len_);
}

void ProgramText::Release(size_t from, size_t to) const {
  if (!map_) return;
  static const auto kPage = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  if (to > map_len_) to = map_len_;
  size_t b = (from + kPage - 1) / kPage * kPage;  // whole pages only
  size_t e = to / kPage * kPage;
  if (e > b) ::madvise(static_cast<char*>(map_) + b, e - b, MADV_DONTNEED);
}

}  // namespace cell::interp
