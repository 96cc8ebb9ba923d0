#include "cell/dashboard/sequence_buffer.h"

namespace cell::dashboard {

SequenceBuffer::SequenceBuffer(std::size_t capacity, int items)
    : capacity_(capacity == 0 ? 1 : capacity), latest_(static_cast<std::size_t>(items)) {
  for (int i = 0; i < items; ++i) latest_[static_cast<std::size_t>(i)].item = i;
}

std::uint64_t SequenceBuffer::Add(Observation o) {
  o.sequence = next_++;
  if (o.item >= 0 && static_cast<std::size_t>(o.item) < latest_.size())
    latest_[static_cast<std::size_t>(o.item)] = o;
  ring_.push_back(std::move(o));
  if (ring_.size() > capacity_) ring_.pop_front();
  return next_ - 1;
}

std::vector<Observation> SequenceBuffer::Range(std::uint64_t from, std::size_t count) const {
  std::vector<Observation> out;
  if (ring_.empty() || from >= next_ || count == 0) return out;
  std::uint64_t first_seq = ring_.front().sequence;
  if (from < first_seq) from = first_seq;
  // Sequences in the ring are contiguous, so the offset is direct.
  for (auto i = static_cast<std::size_t>(from - first_seq); i < ring_.size() && out.size() < count; ++i)
    out.push_back(ring_[i]);
  return out;
}

std::vector<const Observation*> SequenceBuffer::Scan(std::uint64_t from, std::size_t count,
                                                     const std::function<bool(const Observation&)>& match,
                                                     std::uint64_t* next) const {
  std::vector<const Observation*> out;
  *next = next_;
  if (ring_.empty() || from >= next_) return out;
  std::uint64_t first_seq = ring_.front().sequence;
  if (from < first_seq) from = first_seq;
  for (auto i = static_cast<std::size_t>(from - first_seq); i < ring_.size(); ++i) {
    if (out.size() == count) {
      *next = ring_[i].sequence;
      return out;
    }
    if (match(ring_[i])) out.push_back(&ring_[i]);
  }
  return out;
}

}  // namespace cell::dashboard
