#pragma once
// ROS 2 messages are serialised as OMG CDR (XCDR1 "plain CDR", as Fast DDS and Cyclone DDS write them for ROS 2): a
// 4-byte encapsulation header (byte order, options), then the fields in order, each primitive aligned to its own size
// relative to the end of that header (XCDR2 caps the alignment at 4); strings as a uint32 length that counts a
// terminating NUL, then the bytes and the NUL; sequences as a uint32 count, then the elements. ovton reads the few
// sensor_msgs it needs and writes those and the visualisation messages; no ROS library is involved. The reader also
// reads ROS 1's serialisation (no header, no alignment, strings without a NUL), so that ROS 1 bag messages are read
// with the same bounds checks instead of a deserialiser that allocates whatever a damaged length field says.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ovton::core {

/// How a message is serialised: ROS 2's CDR or ROS 1's own format.
enum class Wire { Cdr, Ros1 };

/// Reads one serialised message. Every read is bounds-checked: running past the end, a string without its NUL or a
/// sequence longer than the bytes left throws DataError(file, where + ": ..." naming the byte and the field).
class CdrReader {
public:
  /// `data` holds the message from its encapsulation header. When only the first `size` bytes of a message of
  /// `full_size` bytes are in memory (a reader peeking at an image's header), sequences may extend past `size` up to
  /// `full_size`: seq_bytes() then returns their place without the bytes.
  CdrReader(const uint8_t *data, size_t size, const std::string &file, const std::string &where, size_t full_size = 0,
            Wire wire = Wire::Cdr);
  Wire wire() const { return wire_; }

  uint8_t u8(const char *field);
  bool boolean(const char *field) { return u8(field) != 0; }
  uint32_t u32(const char *field);
  int32_t i32(const char *field);
  double f64(const char *field);
  std::string string(const char *field);
  void f64_array(double *out, size_t n, const char *field);
  /// A sequence's element count, checked against the bytes left for elements of `min_element_bytes` each.
  uint32_t seq_length(size_t min_element_bytes, const char *field);

  /// A uint8[] sequence: where its bytes start (from the message's first byte) and how many; `data` is null when
  /// they lie past the bytes in memory.
  struct Bytes {
    size_t offset = 0, size = 0;
    const uint8_t *data = nullptr;
  };
  Bytes seq_bytes(const char *field);

  /// Bytes read so far, from the message's first byte.
  size_t position() const { return pos_; }
  [[noreturn]] void fail(const std::string &what) const;

private:
  void align(size_t n);
  void need(size_t n, const char *field) const;
  template <typename T> T read(const char *field);

  const uint8_t *data_;
  size_t size_, full_size_, pos_ = 4;
  bool swap_ = false;
  size_t max_align_ = 8;
  Wire wire_ = Wire::Cdr;
  std::string file_, where_;
};

/// Writes one message little-endian (CDR_LE, XCDR1), the encoding rosbag2 records.
class CdrWriter {
public:
  CdrWriter();
  void u8(uint8_t v) { bytes_.push_back(v); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void u32(uint32_t v);
  void i32(int32_t v);
  void f64(double v);
  void string(const std::string &s);
  void f64_array(const double *v, size_t n);
  void seq_length(size_t n);
  void seq_bytes(const uint8_t *data, size_t n);
  const std::vector<uint8_t> &bytes() const { return bytes_; }
  std::vector<uint8_t> take() { return std::move(bytes_); }

private:
  void align(size_t n);
  template <typename T> void put(T v);
  std::vector<uint8_t> bytes_;
};

} // namespace ovton::core
