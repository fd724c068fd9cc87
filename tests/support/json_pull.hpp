// A streaming ("pull") JSON reader with no heap: the golden-data tests walk the reference files
// token by token through a 4 KiB window, so the same test code runs on the host and on a
// microcontroller with a few KiB of RAM.
//
// Numbers: up to 19 significant digits are accumulated exactly and scaled by an exact power of ten
// where possible (|exp| <= 22), giving the correctly rounded double; converting that to float
// recovers the bits of the float32 values the golden files store with 9 significant digits.
#pragma once

#include <cstddef>
#include <cstdint>

namespace ktest {

class JsonReader {
 public:
  JsonReader() = default;
  ~JsonReader();
  JsonReader(const JsonReader&) = delete;
  JsonReader& operator=(const JsonReader&) = delete;

  bool open(const char* path);
  void close();
  bool ok() const { return error_ == nullptr; }
  const char* error() const { return error_ ? error_ : "ok"; }

  /// Consumes '{'.
  bool begin_object();
  /// Next key of the current object (copied to key, truncated to cap-1); false at '}' (consumed).
  bool next_key(char* key, std::size_t cap);
  /// Advances to `key` in the current object, skipping other members; false if the object ends
  /// first (the '}' is consumed then).
  bool find_key(const char* key);
  /// Consumes '['.
  bool begin_array();
  /// True if another element follows in the current array; false at ']' (consumed).
  bool next_element();

  /// Reads a number (null -> NaN, true/false -> 1/0).
  bool read_double(double& v);
  bool read_float(float& v);
  bool read_int(int& v);
  bool read_bool(bool& v);
  bool read_string(char* buf, std::size_t cap);
  /// Reads an array of numbers, flattening nested arrays, into out[0..max). Returns the count read
  /// (elements past max are skipped and counted) or -1 on error.
  int read_numbers(float* out, int max);
  int read_numbers(double* out, int max);
  bool skip_value();
  /// True if the next value is null (not consumed).
  bool peek_null();
  /// The next significant character (not consumed), or 0 at end of input.
  char peek();

 private:
  int get();       // next byte or -1
  int peek_raw();  // next byte without consuming or -1
  void skip_ws();
  bool expect(char c);
  bool fail(const char* msg);
  bool after_value();  // consumes a following ',' if present (inside containers)
  template <typename T>
  int read_numbers_impl(T* out, int max);

  int handle_ = -1;
  char buf_[4096];
  std::size_t len_ = 0, pos_ = 0;
  bool eof_ = false;
  const char* error_ = nullptr;
};

}  // namespace ktest
