// a small RAII layer over the HDF5 C API for the scene, trajectory and run files.
//
// Handles (hid_t) are closed in destructors and are move-only. HDF5's automatic error printing is
// turned off; every failure becomes a divcoll::InputError whose message names the file and the object
// ("runs/a.h5: masses/x0: ..."), with HDF5's own innermost reason appended where it has one.
// Datasets are chunked along their first dimension (about 1 MiB a chunk) with HDF5's Fletcher-32 checksum,
// which HDF5 checks on every read (scalar and empty ones are contiguous); collective writes under MPI-IO; files are opened for serial access unless the caller
// passes a file access property list (e.g. an MPI-IO one). A dataset created in a run file gets the
// attributes of its row of the run-file schema (io/run_file.hpp).
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace divcoll::io::h5 {

using Dims = std::vector<hsize_t>;

// a C++ size as an HDF5 extent
inline hsize_t extent(size_t n) { return static_cast<hsize_t>(n); }

// "(3, 11)"
std::string dims_string(const Dims& d);

// turns HDF5's automatic error printing off for this thread (called by File::open/create)
void quiet_errors();

// one HDF5 identifier and the function that closes it
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer close) : id_(id), close_(close) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = H5I_INVALID_HID; }
  Handle& operator=(Handle&& o) noexcept;
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t id() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // closes now; returns false if HDF5 reported a failure
  bool reset();
  // forgets the identifier without closing it; returns it
  hid_t release() {
    const hid_t id = id_;
    id_ = H5I_INVALID_HID;
    return id;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer close_ = nullptr;
};

// element types the dataset helpers handle
template <class T>
struct is_element : std::false_type {};
template <>
struct is_element<double> : std::true_type {};
template <>
struct is_element<int32_t> : std::true_type {};
template <>
struct is_element<int64_t> : std::true_type {};
template <>
struct is_element<uint8_t> : std::true_type {};
template <>
struct is_element<float> : std::true_type {};

// A check for parallel runs: every rank must make the same HDF5 calls on a file opened with MPI-IO, reads
// included. (A collective call, such as writing an attribute, that misses the metadata cache on some ranks
// only has rank 0 read the entry and broadcast it: caches made unequal by one rank's own reads hang the run
// or hand a rank another entry's bytes.) With DIVCOLL_DEBUG_SYMMETRIC_IO=1 in the environment every Node
// call on such a file is recorded in this process's journal; mpi::check_symmetric_io compares the ranks'.
struct Journal {
  uint64_t calls = 0;                   // calls since the process started
  uint64_t digest = 0;                  // FNV-1a of every call's kind and path, in order
  std::vector<std::string> since_check;  // the calls since the last comparison (at most kKeep)
  static constexpr size_t kKeep = 400;
};
bool journal_enabled();
void enable_journal(bool on);  // for tests: the environment variable's setting, overridden
Journal& journal();

// a file or a group: the object plus the names its error messages use
class Node {
 public:
  hid_t id() const { return handle_.id(); }
  const std::string& file() const { return file_; }
  // "/" for the root, else "/env" etc.
  const std::string& name() const { return name_; }
  // "<file>: <path of child relative to the root>", the prefix of every error message
  std::string where(const std::string& child = "") const;

  // true if `path` (relative, may contain '/') leads to an object
  bool has(const std::string& path) const;
  bool has_attribute(const std::string& attr) const;

  // groups (create makes missing intermediate groups too)
  Node group(const std::string& path) const;
  Node create_group(const std::string& path) const;
  // unlinks the group or dataset `path` if there is one (true: there was); the file keeps its space. The one
  // place where a file's objects are dropped: a stage redone on a copy (--from), a generation written after the
  // last commit. With MPI-IO every rank calls it
  bool remove(const std::string& path) const;
  // removes attribute `attr` if there is one (true: there was)
  bool remove_attribute(const std::string& attr) const;

  // scalar attributes on this object; writing replaces an existing attribute of the same name
  void write_double(const std::string& attr, double v) const;
  void write_int(const std::string& attr, int64_t v) const;
  void write_string(const std::string& attr, const std::string& v) const;  // variable-length UTF-8
  double read_double(const std::string& attr) const;                       // float or integer attribute
  int64_t read_int(const std::string& attr) const;                         // integer attribute
  std::string read_string(const std::string& attr) const;                  // fixed or variable length

  // datasets of double/int32/int64/uint8 (path may contain '/'; missing groups are created).
  // data.size() must be the product of dims; an existing dataset of that name is an error.
  template <class T>
  void write(const std::string& path, const std::vector<T>& data, const Dims& dims) const;
  // creates dataset `path` of `dims` and writes the rows (first index) listed in `rows` from `packed`
  // (those rows one after the other, in any order; a row given twice is refused); an existing dataset of the
  // same dims is written in place. With an MPI-IO file every rank calls it (creation is collective), each
  // with the rows it holds, possibly none, and the transfer is collective.
  template <class T>
  void write_rows(const std::string& path, const Dims& dims, const std::vector<int64_t>& rows,
                  const std::vector<T>& packed) const;
  // dims of a dataset; InputError naming it if it is missing or not a dataset
  Dims dims(const std::string& path) const;
  // the whole dataset converted to T (a float dataset is refused for integer T)
  template <class T>
  std::vector<T> read(const std::string& path, Dims* dims_out = nullptr) const;
  // the same, refused unless its dims equal `expected`
  template <class T>
  std::vector<T> read(const std::string& path, const Dims& expected) const;

 protected:
  Node(Handle h, std::string file, std::string name)
      : handle_(std::move(h)), file_(std::move(file)), name_(std::move(name)) {}
  Handle handle_;
  std::string file_, name_;

  // the object path of `child` relative to the root, for messages
  std::string path_of(const std::string& child) const;
  // in a run file, the schema's attributes (axes, unit, doc, axis labels) on dataset `path`, just created
  // (io/run_file.hpp; nothing in other files)
  void annotate(hid_t dataset, const std::string& path, const char* dtype, const Dims& dims) const;
  static std::string absolute(const std::string& p);
  // records a call on this node in the journal (when enabled and the file is open with MPI-IO)
  void note(const char* op, const std::string& path = "") const;
};

class File : public Node {
 public:
  File(File&&) noexcept = default;
  File& operator=(File&&) noexcept = default;
  // closes the file, except while an exception unwinds the stack through a file opened with MPI-IO:
  // closing is collective, and the other ranks are not closing it, so the handle is left to the process's
  // end (the error path calls MPI_Abort) instead of waiting for ranks that never come
  ~File();
  // creates a new file; refuses an existing one unless overwrite is set (then it is truncated)
  static File create(const std::string& path, bool overwrite, hid_t fapl = H5P_DEFAULT);
  // opens an existing HDF5 file; "X does not exist" / "X is not an HDF5 file" / "cannot open X for
  // writing: <the system's reason>" otherwise
  static File open(const std::string& path, bool writable = false, hid_t fapl = H5P_DEFAULT);
  // flushes and closes, throwing if HDF5 reports a failure (the destructor closes silently)
  void close();
  // closes ignoring failures (e.g. before removing a half-written file); never throws
  void close_quietly() noexcept { handle_.reset(); }

 private:
  using Node::Node;
  bool mpio_ = false;  // opened or created with an MPI-IO file access property list
};

}  // namespace divcoll::io::h5
