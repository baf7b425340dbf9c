// the payloads of plans (stages/plan.hpp): items and results are bytes, binary Boost.Serialization archives of
// plain data (morph::Agent, evo::TrainResult, ...; each stage's own task and result structs beside its plan).
// pack() and unpack() are the only way in and out, for the MPI farm (mpi/protocol.hpp) and the serial farm alike.
#pragma once

#include <boost/archive/binary_iarchive.hpp>
#include <boost/archive/binary_oarchive.hpp>
#include <boost/serialization/array.hpp>
#include <boost/serialization/string.hpp>
#include <boost/serialization/vector.hpp>

#include <istream>
#include <ostream>
#include <streambuf>
#include <string>

#include "morph/agent.hpp"
#include "evo/evolution.hpp"
#include "evo/gd.hpp"

namespace divcoll::stages {

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

// the outcome of one forward episode (an agent alone, a pair or a chain), the result of deployment items
struct EpisodeDone {
  double travel_u = 0, travel_bl = 0;
  uint8_t status = 0;  // sim::Status: 0 ok, 1 nan, 2 unstable
};
template <class Ar>
void serialize(Ar& ar, EpisodeDone& d, unsigned) {
  ar & d.travel_u & d.travel_bl & d.status;
}

}  // namespace divcoll::stages

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
