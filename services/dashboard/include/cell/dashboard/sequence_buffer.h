// The MTConnect agent's observation buffer: every observation gets the next sequence number; the buffer
// keeps the last `capacity` of them for /sample, and the latest observation of every data item for /current
// (also once it has left the buffer, as MTConnect agents do).
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

namespace cell::dashboard {

struct Observation {
  std::uint64_t sequence = 0;
  std::int64_t time_ns = 0;  // wall clock
  int item = 0;              // index into the agent's data item table
  std::string value;         // samples and events; "UNAVAILABLE" when unavailable
  // Conditions: level NORMAL, WARNING, FAULT or UNAVAILABLE, the controller's code and text.
  std::string level;
  std::string native_code;
};

class SequenceBuffer {
 public:
  SequenceBuffer(std::size_t capacity, int items);

  // Stores an observation (its sequence is assigned here) and returns the sequence.
  std::uint64_t Add(Observation o);

  std::size_t capacity() const { return capacity_; }
  // The MTConnect header values: first and last sequence in the buffer, the next to be assigned.
  std::uint64_t first() const { return ring_.empty() ? next_ : ring_.front().sequence; }
  std::uint64_t last() const { return ring_.empty() ? (next_ > 1 ? next_ - 1 : 0) : ring_.back().sequence; }
  std::uint64_t next() const { return next_; }

  // Observations with sequence >= from, at most `count`, in order (from must lie in [first, next]).
  std::vector<Observation> Range(std::uint64_t from, std::size_t count) const;
  // Walks the buffer from `from` on and returns the observations that `match`, at most `count` of them;
  // *next is the sequence after the last one looked at (the client's next `from`).
  std::vector<const Observation*> Scan(std::uint64_t from, std::size_t count,
                                       const std::function<bool(const Observation&)>& match,
                                       std::uint64_t* next) const;
  // The latest observation of each data item (index = item), sequence 0 when it never had one.
  const std::vector<Observation>& Latest() const { return latest_; }

 private:
  std::size_t capacity_;
  std::uint64_t next_ = 1;
  std::deque<Observation> ring_;
  std::vector<Observation> latest_;
};

}  // namespace cell::dashboard
