// the master/worker protocol: message tags and the Boost.Serialization of every payload.
//
//   master → worker   kTask     [first | count | count sizes | count serialized tasks]   a block of items
//   worker → master   kResult   [first | count | count sizes | count serialized results] the block's results
//   master → worker   kRoundEnd (empty)                                                   no more items
//
// A round is collective: every rank enters farm() (mpi/scheduler.hpp) with the same item count. The master
// pushes each worker FarmOptions::depth blocks at once and answers every result with the next block, or,
// once the items are out, with kRoundEnd (once per worker; messages from the master arrive in the order it
// sent them, so no task of this round follows it; the next round's may, as the master can be ahead by rounds:
// a worker matches nothing after its kRoundEnd). The round ends when every item has a result on the master. Payloads
// are binary archives of plain data (morph::Agent, evo::TrainResult, ...) defined below.
#pragma once

#include <boost/archive/binary_iarchive.hpp>
#include <boost/archive/binary_oarchive.hpp>
#include <boost/serialization/array.hpp>
#include <boost/serialization/string.hpp>
#include <boost/serialization/vector.hpp>
#include <mpi.h>

#include <istream>
#include <ostream>
#include <streambuf>
#include <string>

#include "evo/evolution.hpp"
#include "evo/gd.hpp"
#include "io/run_read.hpp"
#include "morph/agent.hpp"
#include "mpi/scheduler.hpp"
#include "mpi/wait.hpp"

namespace divcoll::mpi {

enum Tag : int { kTask = 2, kResult = 3, kRoundEnd = 4 };

// a read-only stream over bytes held elsewhere: unpack reads a payload where it lies (an istringstream
// would copy it first; the master unpacks every result of a round, e.g. 4000 connector gradients of 11.8 kB)
class ByteSource : public std::streambuf {
 public:
  ByteSource(const char* data, size_t size) {
    char* p = const_cast<char*>(data);  // get area only: never written through
    setg(p, p, p + size);
  }
};

// an output stream that appends to a std::string (an ostringstream would copy its buffer out at the end)
class ByteSink : public std::streambuf {
 public:
  explicit ByteSink(std::string& out) : out_(out) {}

 protected:
  int_type overflow(int_type c) override {
    if (!traits_type::eq_int_type(c, traits_type::eof())) out_.push_back(traits_type::to_char_type(c));
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    out_.append(s, static_cast<size_t>(n));
    return n;
  }

 private:
  std::string& out_;
};

template <class T>
std::string pack(const T& v) {
  std::string bytes;
  ByteSink sink(bytes);
  std::ostream os(&sink);
  {
    boost::archive::binary_oarchive ar(os, boost::archive::no_header);
    ar << v;
  }
  return bytes;
}

template <class T>
T unpack(const char* data, size_t size) {
  ByteSource src(data, size);
  std::istream is(&src);
  boost::archive::binary_iarchive ar(is, boost::archive::no_header);
  T v;
  ar >> v;
  return v;
}

template <class T>
T unpack(const std::string& bytes) {
  return unpack<T>(bytes.data(), bytes.size());
}

// rank 0's `value` on every rank (serialized, then broadcast); other ranks' `value` is ignored. The other
// ranks usually arrive first and wait while rank 0 works between rounds: they sleep (wait_sleeping), not
// spin in MPI_Bcast on a core that rank 0 or another job could use
template <class T>
T broadcast(MPI_Comm comm, const T& value) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::string bytes = rank == 0 ? pack(value) : std::string();
  int64_t n = static_cast<int64_t>(bytes.size());
  MPI_Request req;
  MPI_Ibcast(&n, 1, MPI_INT64_T, 0, comm, &req);
  wait_sleeping(req);
  bytes.resize(static_cast<size_t>(n));
  // every rank is here now: the payload goes in one blocking call. A non-blocking broadcast of a large
  // payload moves in segments, each needing both sides in MPI, and a sleeping wait made each segment wait up
  // to the backoff (a 1.3 MB broadcast took 25 ms this way)
  MPI_Bcast(bytes.data(), static_cast<int>(n), MPI_BYTE, 0, comm);
  return unpack<T>(bytes);
}

}  // namespace divcoll::mpi

namespace divcoll::mpi {

// the outcome of one forward episode (an agent alone, a pair or a chain), the result of deployment items
struct EpisodeDone {
  double travel_u = 0, travel_bl = 0;
  uint8_t status = 0;  // sim::Status: 0 ok, 1 nan, 2 unstable
};
template <class Ar>
void serialize(Ar& ar, EpisodeDone& d, unsigned) {
  ar & d.travel_u & d.travel_bl & d.status;
}

// the name lists of stage attributes (io/run_read.hpp)
using io::join;
using io::split;

}  // namespace divcoll::mpi

namespace boost::serialization {

template <class Ar>
void serialize(Ar& ar, divcoll::morph::Anchors& a, unsigned) {
  ar & a.back_foot & a.front_foot & a.back_upper & a.front_upper;
}

template <class Ar>
void serialize(Ar& ar, divcoll::morph::Agent& a, unsigned) {
  ar & a.cells & a.springs & a.rest_pos & a.spring_i & a.spring_j & a.rest_length & a.amplitude & a.params & a.anchors;
}

template <class Ar>
void serialize(Ar& ar, divcoll::evo::TrainResult& r, unsigned) {
  ar & r.travel_u & r.fitness_bl & r.status & r.curve_u & r.nonfinite_gradient_epoch;
}

template <class Ar>
void serialize(Ar& ar, divcoll::evo::Individual& x, unsigned) {
  ar & x.agent & x.id & x.parent & x.train & x.descriptor;
}

}  // namespace boost::serialization
