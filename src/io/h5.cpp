// the RAII layer over the HDF5 C API: handles, attributes, datasets, and HDF5 failures as InputError.
#include "io/h5.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <numeric>

#include "common/check.hpp"
#include "io/run_file.hpp"

namespace divcoll::io::h5 {

namespace {

// the innermost description on HDF5's error stack (the most specific reason), then the stack cleared
std::string hdf5_reason() {
  std::string reason;
  auto walk = [](unsigned n, const H5E_error2_t* err, void* data) -> herr_t {
    if (n == 0 && err && err->desc) *static_cast<std::string*>(data) = err->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, walk, &reason);
  H5Eclear2(H5E_DEFAULT);
  return reason;
}

// throws `sentence` with HDF5's reason appended
[[noreturn]] void fail(const std::string& sentence) {
  const std::string reason = hdf5_reason();
  throw InputError(sentence + (reason.empty() ? "" : " (HDF5: " + reason + ")"));
}

// "<where>: <what>" with HDF5's reason appended
[[noreturn]] void fail(const std::string& where, const std::string& what) { fail(where + ": " + what); }

// memory type, file type and name of each element type
template <class T>
struct Element;
template <>
struct Element<double> {
  static hid_t mem() { return H5T_NATIVE_DOUBLE; }
  static hid_t file() { return H5T_IEEE_F64LE; }
  static constexpr const char* name = "float64";
};
template <>
struct Element<float> {
  static hid_t mem() { return H5T_NATIVE_FLOAT; }
  static hid_t file() { return H5T_IEEE_F32LE; }
  static constexpr const char* name = "float32";
};
template <>
struct Element<int32_t> {
  static hid_t mem() { return H5T_NATIVE_INT32; }
  static hid_t file() { return H5T_STD_I32LE; }
  static constexpr const char* name = "int32";
};
template <>
struct Element<int64_t> {
  static hid_t mem() { return H5T_NATIVE_INT64; }
  static hid_t file() { return H5T_STD_I64LE; }
  static constexpr const char* name = "int64";
};
template <>
struct Element<uint8_t> {
  static hid_t mem() { return H5T_NATIVE_UINT8; }
  static hid_t file() { return H5T_STD_U8LE; }
  static constexpr const char* name = "uint8";
};

const char* class_name(H5T_class_t c) {
  switch (c) {
    case H5T_INTEGER:
      return "integer";
    case H5T_FLOAT:
      return "float";
    case H5T_STRING:
      return "string";
    case H5T_COMPOUND:
      return "compound";
    case H5T_ENUM:
      return "enum";
    case H5T_ARRAY:
      return "array";
    case H5T_VLEN:
      return "variable-length";
    default:
      return "non-numeric";
  }
}

hsize_t product(const Dims& d) {
  hsize_t n = 1;
  for (hsize_t x : d) n *= x;
  return n;
}

// dims of a dataspace; scalar → {}
Dims space_dims(hid_t space, const std::string& where) {
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 0) fail(where, "cannot read the dataspace");
  Dims d(static_cast<size_t>(rank));
  if (rank > 0 && H5Sget_simple_extent_dims(space, d.data(), nullptr) < 0)
    fail(where, "cannot read the dims");
  return d;
}

// a link creation property list that makes missing intermediate groups
Handle intermediate_lcpl(const std::string& where) {
  Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  if (!lcpl.valid() || H5Pset_create_intermediate_group(lcpl.id(), 1) < 0)
    fail(where, "cannot make a link creation property list");
  return lcpl;
}

// a dataset creation property list with HDF5's Fletcher-32 checksum, which HDF5 checks on every read (a
// damaged byte makes the read fail instead of returning a wrong number). The filter needs chunks: along
// the first dimension, about 1 MiB each. Scalar and empty datasets stay contiguous (nothing to check).
Handle checked_dcpl(const Dims& dims, size_t element_bytes, const std::string& where) {
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  if (!dcpl.valid()) fail(where, "cannot make a dataset creation property list");
  if (dims.empty() || product(dims) == 0) return dcpl;
  Dims chunk = dims;
  const hsize_t row_bytes = product(dims) / dims[0] * element_bytes;
  chunk[0] = std::clamp<hsize_t>((hsize_t{1} << 20) / std::max<hsize_t>(row_bytes, 1), 1, dims[0]);
  if (H5Pset_chunk(dcpl.id(), static_cast<int>(chunk.size()), chunk.data()) < 0 || H5Pset_fletcher32(dcpl.id()) < 0)
    fail(where, "cannot set the checksum filter");
  return dcpl;
}

// a transfer property list: collective when the file is open with MPI-IO (every rank writes; filtered
// datasets need it), independent otherwise
Handle transfer_plist(hid_t file_or_object) {
  Handle dxpl(H5Pcreate(H5P_DATASET_XFER), H5Pclose);
  hid_t f = H5Iget_file_id(file_or_object);
  hid_t fapl = H5Fget_access_plist(f);
  if (H5Pget_driver(fapl) == H5FD_MPIO) H5Pset_dxpl_mpio(dxpl.id(), H5FD_MPIO_COLLECTIVE);
  H5Pclose(fapl);
  H5Fclose(f);
  return dxpl;
}

}  // namespace

std::string dims_string(const Dims& d) {
  std::string s = "(";
  for (size_t k = 0; k < d.size(); ++k) s += (k ? ", " : "") + std::to_string(d[k]);
  return s + (d.size() == 1 ? ",)" : ")");
}

void quiet_errors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

// ---- Handle ------------------------------------------------------------------------------------

Handle& Handle::operator=(Handle&& o) noexcept {
  if (this != &o) {
    reset();
    id_ = o.id_;
    close_ = o.close_;
    o.id_ = H5I_INVALID_HID;
  }
  return *this;
}

bool Handle::reset() {
  bool ok = true;
  if (id_ >= 0 && close_) ok = close_(id_) >= 0;
  id_ = H5I_INVALID_HID;
  return ok;
}

// ---- Node: names -------------------------------------------------------------------------------

std::string Node::path_of(const std::string& child) const {
  if (name_ == "/") return child;
  const std::string self = name_.substr(1);
  return child.empty() ? self : self + "/" + child;
}

// "/" + p, built by append (GCC 12 warns falsely on "/" + std::string&&, bug 105329)
std::string Node::absolute(const std::string& p) {
  std::string s(1, '/');
  s.append(p);
  return s;
}

std::string Node::where(const std::string& child) const {
  const std::string p = path_of(child);
  return p.empty() ? file_ : file_ + ": " + p;
}

// ---- the journal of calls on MPI-IO files (DIVCOLL_DEBUG_SYMMETRIC_IO=1) -------------------------

namespace {
// the paths of the files this process has open with MPI-IO (H5Fget_access_plist, which would tell, is itself
// collective for such a file)
std::vector<std::string>& mpio_files() {
  static std::vector<std::string> v;
  return v;
}
void set_mpio(const std::string& path, bool on) {
  auto& v = mpio_files();
  const auto it = std::find(v.begin(), v.end(), path);
  if (on && it == v.end()) v.push_back(path);
  if (!on && it != v.end()) v.erase(it);
}

bool& journal_flag() {
  static bool on = [] {
    const char* e = std::getenv("DIVCOLL_DEBUG_SYMMETRIC_IO");
    return e != nullptr && std::string(e) == "1";
  }();
  return on;
}
}  // namespace

bool journal_enabled() { return journal_flag(); }
void enable_journal(bool on) { journal_flag() = on; }

Journal& journal() {
  static Journal j;
  return j;
}

void Node::note(const char* op, const std::string& path) const {
  if (!journal_enabled()) return;
  const auto& files = mpio_files();
  if (std::find(files.begin(), files.end(), file_) == files.end()) return;
  const std::string line = std::string(op) + " " + (name_ == "/" ? "" : name_) + (path.empty() ? "" : "/" + path);
  Journal& j = journal();
  ++j.calls;
  for (unsigned char c : line + "\n") j.digest = (j.digest ^ c) * 1099511628211ull;
  if (j.since_check.size() < Journal::kKeep) j.since_check.push_back(line);
}

namespace {
std::string attr_label(const std::string& node_name, const std::string& attr) {
  return "attribute '" + attr + "'" + (node_name == "/" ? "" : " of " + node_name.substr(1));
}
}  // namespace

// ---- Node: links and groups --------------------------------------------------------------------

bool Node::has(const std::string& path) const {
  note("has", path);
  // check every prefix: H5Lexists fails (rather than returning false) if a parent is missing
  size_t pos = 0;
  while (true) {
    const size_t slash = path.find('/', pos);
    const std::string prefix = path.substr(0, slash);
    const htri_t e = H5Lexists(id(), prefix.c_str(), H5P_DEFAULT);
    if (e <= 0) {
      H5Eclear2(H5E_DEFAULT);
      return false;
    }
    if (slash == std::string::npos) break;
    pos = slash + 1;
  }
  const htri_t o = H5Oexists_by_name(id(), path.c_str(), H5P_DEFAULT);
  if (o <= 0) H5Eclear2(H5E_DEFAULT);
  return o > 0;
}

bool Node::has_attribute(const std::string& attr) const {
  note("has_attribute", attr);
  const htri_t e = H5Aexists(id(), attr.c_str());
  if (e < 0) fail(file_, "cannot look up " + attr_label(name_, attr));
  return e > 0;
}

Node Node::group(const std::string& path) const {
  note("group", path);
  if (!has(path)) throw InputError(file_ + ": missing group " + path_of(path));
  Handle g(H5Gopen2(id(), path.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g.valid()) fail(where(path) + " is not a group");
  return Node(std::move(g), file_, absolute(path_of(path)));
}

Node Node::create_group(const std::string& path) const {
  note("create_group", path);
  if (has(path)) throw InputError(where(path) + ": already exists");
  Handle lcpl = intermediate_lcpl(where(path));
  Handle g(H5Gcreate2(id(), path.c_str(), lcpl.id(), H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!g.valid()) fail(where(path), "cannot create the group");
  return Node(std::move(g), file_, absolute(path_of(path)));
}

bool Node::remove(const std::string& path) const {
  note("remove", path);
  if (!has(path)) return false;
  if (H5Ldelete(id(), path.c_str(), H5P_DEFAULT) < 0) fail(where(path), "cannot remove it");
  return true;
}

bool Node::remove_attribute(const std::string& attr) const {
  note("remove_attribute", attr);
  if (!has_attribute(attr)) return false;
  if (H5Adelete(id(), attr.c_str()) < 0) fail(file_, "cannot remove " + attr_label(name_, attr));
  return true;
}

// ---- Node: attributes --------------------------------------------------------------------------

namespace {

// creates (replacing) a scalar attribute of file type `ftype` and writes `buf` of memory type `mtype`
void write_scalar_attribute(hid_t obj, const std::string& attr, hid_t ftype, hid_t mtype, const void* buf,
                            const std::string& where) {
  const htri_t e = H5Aexists(obj, attr.c_str());
  if (e < 0 || (e > 0 && H5Adelete(obj, attr.c_str()) < 0)) fail(where, "cannot replace it");
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle a(H5Acreate2(obj, attr.c_str(), ftype, space.id(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!a.valid()) fail(where, "cannot create it");
  if (H5Awrite(a.id(), mtype, buf) < 0) fail(where, "cannot write it");
  if (!a.reset()) fail(where, "cannot close it");
}

// opens an attribute holding exactly one value; returns it with its file type class
Handle open_scalar_attribute(hid_t obj, const std::string& attr, const std::string& where, Handle& ftype) {
  const htri_t e = H5Aexists(obj, attr.c_str());
  if (e < 0) fail(where, "cannot look it up");
  if (e == 0) throw InputError(where + " is missing");
  Handle a(H5Aopen(obj, attr.c_str(), H5P_DEFAULT), H5Aclose);
  if (!a.valid()) fail(where, "cannot open it");
  Handle space(H5Aget_space(a.id()), H5Sclose);
  const hssize_t n = space.valid() ? H5Sget_simple_extent_npoints(space.id()) : -1;
  if (n != 1) fail(where + " must hold exactly one value (it holds " + std::to_string(n) + ")");
  ftype = Handle(H5Aget_type(a.id()), H5Tclose);
  if (!ftype.valid()) fail(where, "cannot read its type");
  return a;
}

}  // namespace

void Node::write_double(const std::string& attr, double v) const {
  note("write_double", attr);
  write_scalar_attribute(id(), attr, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v,
                         file_ + ": " + attr_label(name_, attr));
}

void Node::write_int(const std::string& attr, int64_t v) const {
  note("write_int", attr);
  write_scalar_attribute(id(), attr, H5T_STD_I64LE, H5T_NATIVE_INT64, &v,
                         file_ + ": " + attr_label(name_, attr));
}

namespace {
// a variable-length UTF-8 string attribute (replacing one of the same name)
void write_string_attribute(hid_t obj, const std::string& attr, const std::string& v, const std::string& where) {
  Handle t(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!t.valid() || H5Tset_size(t.id(), H5T_VARIABLE) < 0 || H5Tset_cset(t.id(), H5T_CSET_UTF8) < 0)
    fail(where, "cannot make a string type");
  const char* p = v.c_str();
  write_scalar_attribute(obj, attr, t.id(), t.id(), &p, where);
}
}  // namespace

void Node::write_string(const std::string& attr, const std::string& v) const {
  note("write_string", attr);
  write_string_attribute(id(), attr, v, file_ + ": " + attr_label(name_, attr));
}

double Node::read_double(const std::string& attr) const {
  note("read_double", attr);
  const std::string w = file_ + ": " + attr_label(name_, attr);
  Handle ftype;
  Handle a = open_scalar_attribute(id(), attr, w, ftype);
  const H5T_class_t c = H5Tget_class(ftype.id());
  if (c != H5T_FLOAT && c != H5T_INTEGER)
    throw InputError(w + " must be a number (it is " + class_name(c) + ")");
  double v = 0;
  if (H5Aread(a.id(), H5T_NATIVE_DOUBLE, &v) < 0) fail(w, "cannot read it");
  return v;
}

int64_t Node::read_int(const std::string& attr) const {
  note("read_int", attr);
  const std::string w = file_ + ": " + attr_label(name_, attr);
  Handle ftype;
  Handle a = open_scalar_attribute(id(), attr, w, ftype);
  const H5T_class_t c = H5Tget_class(ftype.id());
  if (c != H5T_INTEGER) throw InputError(w + " must be an integer (it is " + class_name(c) + ")");
  int64_t v = 0;
  if (H5Aread(a.id(), H5T_NATIVE_INT64, &v) < 0) fail(w, "cannot read it");
  return v;
}

std::string Node::read_string(const std::string& attr) const {
  note("read_string", attr);
  const std::string w = file_ + ": " + attr_label(name_, attr);
  Handle ftype;
  Handle a = open_scalar_attribute(id(), attr, w, ftype);
  const H5T_class_t c = H5Tget_class(ftype.id());
  if (c != H5T_STRING) throw InputError(w + " must be a string (it is " + class_name(c) + ")");
  const htri_t vlen = H5Tis_variable_str(ftype.id());
  if (vlen < 0) fail(w, "cannot read its string type");
  if (vlen > 0) {
    // variable length: HDF5 allocates, we free
    Handle mt(H5Tcopy(H5T_C_S1), H5Tclose);
    if (!mt.valid() || H5Tset_size(mt.id(), H5T_VARIABLE) < 0 ||
        H5Tset_cset(mt.id(), H5Tget_cset(ftype.id())) < 0)
      fail(w, "cannot make a string type");
    char* p = nullptr;
    if (H5Aread(a.id(), mt.id(), &p) < 0) fail(w, "cannot read it");
    std::string s = p ? p : "";
    H5free_memory(p);
    return s;
  }
  // fixed length: read with the file's own type, then cut at the first NUL and trailing pad spaces
  const size_t n = H5Tget_size(ftype.id());
  std::string buf(n, '\0');
  if (n > 0 && H5Aread(a.id(), ftype.id(), buf.data()) < 0) fail(w, "cannot read it");
  buf.resize(std::min(buf.find('\0'), buf.size()));
  if (H5Tget_strpad(ftype.id()) == H5T_STR_SPACEPAD) {
    while (!buf.empty() && buf.back() == ' ') buf.pop_back();
  }
  return buf;
}

// ---- Node: datasets ----------------------------------------------------------------------------

void Node::annotate(hid_t dataset, const std::string& path, const char* dtype, const Dims& dims) const {
  Handle r(H5Gopen2(id(), "/", H5P_DEFAULT), H5Gclose);
  if (!r.valid()) fail(where(path), "cannot open the root group");
  const Node root(std::move(r), file_, "/");
  for (const auto& [attr, v] : run_file::attributes(root, path_of(path), dtype, dims))
    write_string_attribute(dataset, attr, v, where(path) + ": attribute " + attr);
}

template <class T>
void Node::write(const std::string& path, const std::vector<T>& data, const Dims& dims) const {
  note("write", path);
  static_assert(is_element<T>::value, "h5 datasets hold double, float, int32, int64 or uint8");
  const std::string w = where(path);
  if (product(dims) != data.size())
    throw InputError(w + ": " + std::to_string(data.size()) + " values do not fill dims " +
                     dims_string(dims));
  if (has(path)) throw InputError(w + ": already exists");
  Handle space(dims.empty() ? H5Screate(H5S_SCALAR)
                            : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
               H5Sclose);
  if (!space.valid()) fail(w, "cannot make a dataspace of dims " + dims_string(dims));
  Handle lcpl = intermediate_lcpl(w);
  Handle dcpl = checked_dcpl(dims, sizeof(T), w);
  Handle d(
      H5Dcreate2(id(), path.c_str(), Element<T>::file(), space.id(), lcpl.id(), dcpl.id(), H5P_DEFAULT),
      H5Dclose);
  if (!d.valid()) fail(w, "cannot create the dataset");
  annotate(d.id(), path, Element<T>::name, dims);
  // an empty selection needs no write (and HDF5 1.10 refuses a null buffer)
  if (!data.empty() && H5Dwrite(d.id(), Element<T>::mem(), H5S_ALL, H5S_ALL, transfer_plist(id()).id(), data.data()) < 0)
    fail(w, "cannot write the dataset");
  if (!d.reset()) fail(w, "cannot close the dataset");
}

template <class T>
void Node::write_rows(const std::string& path, const Dims& dims, const std::vector<int64_t>& rows_given,
                      const std::vector<T>& packed_given) const {
  note("write_rows", path);
  const std::string w = where(path);
  if (dims.empty()) throw InputError(w + ": write_rows needs at least one dimension");
  const hsize_t row_size = product(dims) / std::max<hsize_t>(dims[0], 1);
  if (packed_given.size() != rows_given.size() * row_size)
    throw InputError(w + ": " + std::to_string(packed_given.size()) + " values do not fill " +
                     std::to_string(rows_given.size()) + " rows of " + dims_string(dims));
  // HDF5 fills a selection in the file's order, so rows not given in ascending order are sorted, their values
  // with them (else row 5's values would land in row 1 for rows {5, 1}); a row given twice is refused
  std::vector<int64_t> sorted_rows;
  std::vector<T> sorted_packed;
  const bool ascending = std::is_sorted(rows_given.begin(), rows_given.end());
  if (!ascending) {
    std::vector<size_t> order(rows_given.size());
    std::iota(order.begin(), order.end(), size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return rows_given[a] < rows_given[b]; });
    sorted_packed.reserve(packed_given.size());
    for (size_t k : order) {
      sorted_rows.push_back(rows_given[k]);
      sorted_packed.insert(sorted_packed.end(), packed_given.begin() + static_cast<std::ptrdiff_t>(k * row_size),
                           packed_given.begin() + static_cast<std::ptrdiff_t>((k + 1) * row_size));
    }
  }
  const std::vector<int64_t>& rows = ascending ? rows_given : sorted_rows;
  const std::vector<T>& packed = ascending ? packed_given : sorted_packed;
  if (std::adjacent_find(rows.begin(), rows.end()) != rows.end())
    throw InputError(w + ": a row is given twice");
  Handle fspace(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  if (!fspace.valid()) fail(w, "cannot make a dataspace of dims " + dims_string(dims));
  // creation is collective: every rank of the file's communicator calls this; an existing dataset of the
  // same dims is written in place (checkpointed state, curves filled as a run goes)
  Handle d;
  if (has(path)) {
    if (this->dims(path) != dims) throw InputError(w + ": exists with dims " + dims_string(this->dims(path)) +
                                                   ", not " + dims_string(dims));
    d = Handle(H5Dopen2(id(), path.c_str(), H5P_DEFAULT), H5Dclose);
    // (a dataset created just before a kill may lack the schema's attributes)
    if (d.valid() && H5Aexists(d.id(), "axes") == 0) annotate(d.id(), path, Element<T>::name, dims);
  } else {
    Handle lcpl = intermediate_lcpl(w);
    Handle dcpl = checked_dcpl(dims, sizeof(T), w);
    d = Handle(H5Dcreate2(id(), path.c_str(), Element<T>::file(), fspace.id(), lcpl.id(), dcpl.id(), H5P_DEFAULT),
               H5Dclose);
    if (d.valid()) annotate(d.id(), path, Element<T>::name, dims);
  }
  if (!d.valid()) fail(w, "cannot create the dataset");
  // this rank's rows: one block if they are one run (r, r + 1, ...), with a memory space of the block's
  // shape, so that HDF5 maps the transfer to the chunks block by block (element by element, the agents
  // stage's 126 pool datasets took 58 ms to write at quick scale, 36 ms this way); else a union of one-row
  // hyperslabs (or none). The same values land in the same places either way
  // (rows are ascending and distinct here: the first and the last bound them, and they are one run when
  // they span as many rows as there are)
  if (!rows.empty() && (rows.front() < 0 || static_cast<hsize_t>(rows.back()) >= dims[0]))
    throw InputError(w + ": row out of range");
  Dims start(dims.size(), 0), count = dims;
  count[0] = 1;
  const bool run = !rows.empty() && !packed.empty() && rows.back() - rows.front() + 1 == static_cast<int64_t>(rows.size());
  if (run) {
    start[0] = static_cast<hsize_t>(rows.front());
    count[0] = rows.size();
    if (H5Sselect_hyperslab(fspace.id(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr) < 0)
      fail(w, "cannot select rows");
  } else if (rows.empty()) {
    H5Sselect_none(fspace.id());
  } else {
    for (size_t q = 0; q < rows.size(); ++q) {
      start[0] = static_cast<hsize_t>(rows[q]);
      if (H5Sselect_hyperslab(fspace.id(), q == 0 ? H5S_SELECT_SET : H5S_SELECT_OR, start.data(), nullptr,
                              count.data(), nullptr) < 0)
        fail(w, "cannot select rows");
    }
  }
  const hsize_t n_mem = std::max<hsize_t>(packed.size(), 1);
  Handle mspace(run ? H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr)
                    : H5Screate_simple(1, &n_mem, nullptr),
                H5Sclose);
  if (rows.empty()) H5Sselect_none(mspace.id());
  // a collective transfer when the file is open with MPI-IO, independent otherwise
  Handle dxpl(H5Pcreate(H5P_DATASET_XFER), H5Pclose);
  hid_t fapl = H5Fget_access_plist(id());
  const bool mpio = H5Pget_driver(fapl) == H5FD_MPIO;
  H5Pclose(fapl);
  if (mpio) H5Pset_dxpl_mpio(dxpl.id(), H5FD_MPIO_COLLECTIVE);
  const T dummy{};
  if (H5Dwrite(d.id(), Element<T>::mem(), mspace.id(), fspace.id(), dxpl.id(), packed.empty() ? &dummy : packed.data()) <
      0)
    fail(w, "cannot write the dataset");
  if (!d.reset()) fail(w, "cannot close the dataset");
}

Dims Node::dims(const std::string& path) const {
  note("dims", path);
  const std::string w = where(path);
  if (!has(path)) throw InputError(file_ + ": missing dataset " + path_of(path));
  Handle d(H5Dopen2(id(), path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.valid()) fail(w + " is not a dataset");
  Handle space(H5Dget_space(d.id()), H5Sclose);
  if (!space.valid()) fail(w, "cannot read the dataspace");
  return space_dims(space.id(), w);
}

template <class T>
std::vector<T> Node::read(const std::string& path, Dims* dims_out) const {
  note("read", path);
  static_assert(is_element<T>::value, "h5 datasets hold double, float, int32, int64 or uint8");
  const std::string w = where(path);
  if (!has(path)) throw InputError(file_ + ": missing dataset " + path_of(path));
  Handle d(H5Dopen2(id(), path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.valid()) fail(w + " is not a dataset");
  Handle space(H5Dget_space(d.id()), H5Sclose);
  if (!space.valid()) fail(w, "cannot read the dataspace");
  const Dims dd = space_dims(space.id(), w);
  if (dims_out) *dims_out = dd;

  // element class: integers may be read as double, floats never as integers
  Handle ftype(H5Dget_type(d.id()), H5Tclose);
  if (!ftype.valid()) fail(w, "cannot read the element type");
  const H5T_class_t c = H5Tget_class(ftype.id());
  const bool is_float = std::is_floating_point_v<T>;
  if (!(c == H5T_INTEGER || (is_float && c == H5T_FLOAT)))
    throw InputError(w + " has " + class_name(c) + " elements, expected " + Element<T>::name);

  const size_t n = static_cast<size_t>(product(dd));
  std::vector<T> out(n);
  if (n == 0) return out;
  if constexpr (std::is_same_v<T, double> || std::is_same_v<T, int64_t> || std::is_same_v<T, float>) {
    // (a float read of a double dataset rounds to nearest, as a cast would)
    if (H5Dread(d.id(), Element<T>::mem(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
      fail(w, "cannot read the dataset");
  } else {
    // narrow integers: read wide and check the range (HDF5 would clamp silently)
    std::vector<int64_t> wide(n);
    if (H5Dread(d.id(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, wide.data()) < 0)
      fail(w, "cannot read the dataset");
    for (size_t k = 0; k < n; ++k) {
      if (wide[k] < std::numeric_limits<T>::min() || wide[k] > std::numeric_limits<T>::max())
        throw InputError(w + "[" + std::to_string(k) + "] = " + std::to_string(wide[k]) + " does not fit " +
                         Element<T>::name);
      out[k] = static_cast<T>(wide[k]);
    }
  }
  return out;
}

template <class T>
std::vector<T> Node::read(const std::string& path, const Dims& expected) const {
  const Dims found = dims(path);
  if (found != expected)
    throw InputError(where(path) + " has shape " + dims_string(found) + ", expected " +
                     dims_string(expected));
  return read<T>(path);
}

#define DIVCOLL_H5_INSTANTIATE(T)                                                             \
  template void Node::write<T>(const std::string&, const std::vector<T>&, const Dims&) const; \
  template void Node::write_rows<T>(const std::string&, const Dims&, const std::vector<int64_t>&,        \
                                    const std::vector<T>&) const;                                      \
  template std::vector<T> Node::read<T>(const std::string&, Dims*) const;                     \
  template std::vector<T> Node::read<T>(const std::string&, const Dims&) const;
DIVCOLL_H5_INSTANTIATE(double)
DIVCOLL_H5_INSTANTIATE(int32_t)
DIVCOLL_H5_INSTANTIATE(int64_t)
DIVCOLL_H5_INSTANTIATE(uint8_t)
DIVCOLL_H5_INSTANTIATE(float)
#undef DIVCOLL_H5_INSTANTIATE

// ---- File --------------------------------------------------------------------------------------

File File::create(const std::string& path, bool overwrite, hid_t fapl) {
  quiet_errors();
  std::error_code ec;
  if (!overwrite && std::filesystem::exists(path, ec))
    throw InputError(path + " already exists (refusing to overwrite it)");
  if (std::filesystem::is_directory(path, ec)) throw InputError(path + " is a directory");
  Handle f(H5Fcreate(path.c_str(), overwrite ? H5F_ACC_TRUNC : H5F_ACC_EXCL, H5P_DEFAULT, fapl), H5Fclose);
  if (!f.valid()) fail(path, "cannot create the HDF5 file");
  File out(std::move(f), path, "/");
  out.mpio_ = fapl != H5P_DEFAULT && H5Pget_driver(fapl) == H5FD_MPIO;
  if (out.mpio_) set_mpio(path, true);
  return out;
}

File File::open(const std::string& path, bool writable, hid_t fapl) {
  quiet_errors();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path + " does not exist");
  if (std::filesystem::is_directory(path, ec)) throw InputError(path + " is a directory, not an HDF5 file");
  // the system's own reason (permissions, an immutable file, a read-only file system) before HDF5's guess
  const int fd = ::open(path.c_str(), writable ? O_RDWR : O_RDONLY);
  if (fd < 0) {
    const int err = errno;
    H5Eclear2(H5E_DEFAULT);
    throw InputError(path + ": cannot open it " + (writable ? "for writing" : "for reading") + ": " +
                     std::strerror(err) +
                     (err == EPERM && writable ? " (is it immutable? see lsattr)" : ""));
  }
  ::close(fd);
  const htri_t is = H5Fis_hdf5(path.c_str());
  if (is == 0) {
    H5Eclear2(H5E_DEFAULT);
    throw InputError(path + " is not an HDF5 file");
  }
  if (is < 0) fail(path + " cannot be read as an HDF5 file");
  Handle f(H5Fopen(path.c_str(), writable ? H5F_ACC_RDWR : H5F_ACC_RDONLY, fapl), H5Fclose);
  if (!f.valid()) fail(path + " is not a readable HDF5 file (truncated or damaged?)");
  File out(std::move(f), path, "/");
  out.mpio_ = fapl != H5P_DEFAULT && H5Pget_driver(fapl) == H5FD_MPIO;
  if (out.mpio_) set_mpio(path, true);
  return out;
}

File::~File() {
  if (mpio_ && handle_.valid()) set_mpio(file_, false);
  // (H5Fget_access_plist would duplicate the communicator: collective, so it cannot be asked here)
  if (std::uncaught_exceptions() > 0 && mpio_ && handle_.valid()) {
    (void)handle_.release();
    return;
  }
  handle_.reset();
}

void File::close() {
  if (!handle_.valid()) return;
  if (mpio_) set_mpio(file_, false);
  if (H5Fflush(handle_.id(), H5F_SCOPE_LOCAL) < 0) fail(file_, "cannot flush the file");
  if (!handle_.reset()) fail(file_, "cannot close the file");
}

}  // namespace divcoll::io::h5
