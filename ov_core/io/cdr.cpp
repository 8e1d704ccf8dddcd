#include "ov_core/io/cdr.h"
#include "ov_core/types/errors.h"

#include <cstdio>
#include <cstring>

namespace ovton::core {

namespace {

template <typename T> T byte_swapped(T v) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (size_t i = 0; i < sizeof(T) / 2; ++i)
    std::swap(b[i], b[sizeof(T) - 1 - i]);
  std::memcpy(&v, b, sizeof(T));
  return v;
}

bool host_little_endian() {
  const uint16_t one = 1;
  uint8_t b;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

} // namespace

CdrReader::CdrReader(const uint8_t *data, size_t size, const std::string &file, const std::string &where,
                     size_t full_size, Wire wire)
    : data_(data), size_(size), full_size_(full_size > size ? full_size : size), wire_(wire), file_(file),
      where_(where) {
  if (wire == Wire::Ros1) { // little-endian, packed, from the first byte
    pos_ = 0;
    max_align_ = 1;
    swap_ = !host_little_endian();
    return;
  }
  if (size < 4)
    fail("a CDR message of " + std::to_string(size) + " bytes has no encapsulation header");
  // Representation identifier (big-endian): 0/1 plain CDR big/little endian, 6/7 XCDR2 plain big/little endian.
  const unsigned id = static_cast<unsigned>(data[0]) << 8 | data[1];
  if (id != 0 && id != 1 && id != 6 && id != 7) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%04x", id);
    fail(std::string("unsupported CDR encapsulation ") + hex +
         " (supported: plain CDR and XCDR2, either byte order; parameter lists are not)");
  }
  const bool little = (id & 1) != 0;
  swap_ = little != host_little_endian();
  max_align_ = id >= 6 ? 4 : 8;
}

void CdrReader::fail(const std::string &what) const {
  throw DataError(file_, where_ + ": " + what);
}

void CdrReader::align(size_t n) {
  n = n < max_align_ ? n : max_align_;
  const size_t rel = pos_ - 4; // alignment counts from the end of the encapsulation header (1 for ROS 1: none)
  pos_ += (n - rel % n) % n;
}

void CdrReader::need(size_t n, const char *field) const {
  if (pos_ > size_ || n > size_ - pos_)
    fail(std::string("message ends at byte ") + std::to_string(size_) + " while reading " + field + " (" +
         std::to_string(n) + " bytes at byte " + std::to_string(pos_) + "): truncated or not this message type");
}

template <typename T> T CdrReader::read(const char *field) {
  align(sizeof(T));
  need(sizeof(T), field);
  T v;
  std::memcpy(&v, data_ + pos_, sizeof(T));
  pos_ += sizeof(T);
  return swap_ ? byte_swapped(v) : v;
}

uint8_t CdrReader::u8(const char *field) {
  return read<uint8_t>(field);
}
uint32_t CdrReader::u32(const char *field) {
  return read<uint32_t>(field);
}
int32_t CdrReader::i32(const char *field) {
  return read<int32_t>(field);
}
double CdrReader::f64(const char *field) {
  return read<double>(field);
}

std::string CdrReader::string(const char *field) {
  const uint32_t n = u32(field);
  need(n, field);
  if (wire_ == Wire::Ros1) {
    pos_ += n;
    return std::string(reinterpret_cast<const char *>(data_ + pos_ - n), n);
  }
  if (n == 0) // some writers give an empty string no terminator at all
    return std::string();
  if (data_[pos_ + n - 1] != 0)
    fail(std::string("string ") + field + " at byte " + std::to_string(pos_) + " lacks its terminating NUL");
  std::string s(reinterpret_cast<const char *>(data_ + pos_), n - 1);
  pos_ += n;
  return s;
}

void CdrReader::f64_array(double *out, size_t n, const char *field) {
  for (size_t i = 0; i < n; ++i)
    out[i] = f64(field);
}

uint32_t CdrReader::seq_length(size_t min_element_bytes, const char *field) {
  const uint32_t n = u32(field);
  if (min_element_bytes > 0 && static_cast<uint64_t>(n) * min_element_bytes > size_ - pos_)
    fail(std::string("sequence ") + field + " declares " + std::to_string(n) + " elements, more than the " +
         std::to_string(size_ - pos_) + " bytes left hold");
  return n;
}

CdrReader::Bytes CdrReader::seq_bytes(const char *field) {
  const uint32_t n = u32(field);
  if (n > full_size_ - pos_)
    fail(std::string("sequence ") + field + " declares " + std::to_string(n) + " bytes, the message holds " +
         std::to_string(full_size_ - pos_) + " after byte " + std::to_string(pos_) + ": truncated");
  Bytes b;
  b.offset = pos_;
  b.size = n;
  b.data = n <= size_ - pos_ ? data_ + pos_ : nullptr;
  pos_ += n;
  return b;
}

CdrWriter::CdrWriter() {
  bytes_ = {0x00, 0x01, 0x00, 0x00}; // CDR_LE, no options
}

void CdrWriter::align(size_t n) {
  while ((bytes_.size() - 4) % n)
    bytes_.push_back(0);
}

template <typename T> void CdrWriter::put(T v) {
  align(sizeof(T));
  if (!host_little_endian())
    v = byte_swapped(v);
  const size_t at = bytes_.size();
  bytes_.resize(at + sizeof(T));
  std::memcpy(bytes_.data() + at, &v, sizeof(T));
}

void CdrWriter::u32(uint32_t v) {
  put(v);
}
void CdrWriter::i32(int32_t v) {
  put(v);
}
void CdrWriter::f64(double v) {
  put(v);
}

void CdrWriter::string(const std::string &s) {
  u32(static_cast<uint32_t>(s.size() + 1));
  bytes_.insert(bytes_.end(), s.begin(), s.end());
  bytes_.push_back(0);
}

void CdrWriter::f64_array(const double *v, size_t n) {
  for (size_t i = 0; i < n; ++i)
    f64(v[i]);
}

void CdrWriter::seq_length(size_t n) {
  u32(static_cast<uint32_t>(n));
}

void CdrWriter::seq_bytes(const uint8_t *data, size_t n) {
  seq_length(n);
  bytes_.insert(bytes_.end(), data, data + n);
}

} // namespace ovton::core
