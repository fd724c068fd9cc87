#include "json_pull.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "test_io.hpp"

namespace ktest {

JsonReader::~JsonReader() { close(); }

bool JsonReader::open(const char* path) {
  close();
  error_ = nullptr;
  len_ = pos_ = 0;
  eof_ = false;
  handle_ = file_open(path);
  if (handle_ < 0) return fail("cannot open file");
  return true;
}

void JsonReader::close() {
  if (handle_ >= 0) file_close(handle_);
  handle_ = -1;
}

bool JsonReader::fail(const char* msg) {
  if (error_ == nullptr) error_ = msg;
  return false;
}

int JsonReader::peek_raw() {
  if (pos_ >= len_) {
    if (eof_ || handle_ < 0) return -1;
    const long n = file_read(handle_, buf_, sizeof(buf_));
    if (n <= 0) {
      eof_ = true;
      return -1;
    }
    len_ = static_cast<std::size_t>(n);
    pos_ = 0;
  }
  return static_cast<unsigned char>(buf_[pos_]);
}

int JsonReader::get() {
  const int c = peek_raw();
  if (c >= 0) ++pos_;
  return c;
}

void JsonReader::skip_ws() {
  for (;;) {
    const int c = peek_raw();
    if (c == ' ' || c == '\n' || c == '\r' || c == '\t') {
      ++pos_;
    } else {
      return;
    }
  }
}

char JsonReader::peek() {
  skip_ws();
  const int c = peek_raw();
  return c < 0 ? '\0' : static_cast<char>(c);
}

bool JsonReader::expect(char c) {
  skip_ws();
  if (get() != c) return fail("unexpected character");
  return true;
}

bool JsonReader::after_value() {
  skip_ws();
  if (peek_raw() == ',') ++pos_;
  return ok();
}

bool JsonReader::begin_object() { return ok() && expect('{'); }
bool JsonReader::begin_array() { return ok() && expect('['); }

bool JsonReader::next_key(char* key, std::size_t cap) {
  if (!ok()) return false;
  skip_ws();
  if (peek_raw() == '}') {
    ++pos_;
    after_value();
    return false;
  }
  if (!read_string(key, cap)) return false;
  // read_string consumed a trailing ',' if any, which cannot follow a key: check ':'.
  return expect(':');
}

bool JsonReader::find_key(const char* key) {
  char k[96];
  while (next_key(k, sizeof(k))) {
    if (std::strcmp(k, key) == 0) return true;
    if (!skip_value()) return false;
  }
  return false;
}

bool JsonReader::next_element() {
  if (!ok()) return false;
  skip_ws();
  const int c = peek_raw();
  if (c == ']') {
    ++pos_;
    after_value();
    return false;
  }
  if (c < 0) return fail("unexpected end of input in array");
  return true;
}

bool JsonReader::peek_null() { return peek() == 'n'; }

bool JsonReader::read_string(char* out, std::size_t cap) {
  if (!expect('"')) return false;
  std::size_t n = 0;
  for (;;) {
    int c = get();
    if (c < 0) return fail("unterminated string");
    if (c == '"') break;
    if (c == '\\') {
      c = get();
      if (c == 'u') {  // keep it simple: \uXXXX -> '?'
        for (int i = 0; i < 4; ++i) get();
        c = '?';
      } else if (c == 'n') {
        c = '\n';
      } else if (c == 't') {
        c = '\t';
      }
    }
    if (out != nullptr && n + 1 < cap) out[n++] = static_cast<char>(c);
  }
  if (out != nullptr && cap > 0) out[n] = '\0';
  // A string used as a value may be followed by ','; a key is followed by ':' (left alone).
  skip_ws();
  if (peek_raw() == ',') ++pos_;
  return true;
}

bool JsonReader::read_double(double& v) {
  if (!ok()) return false;
  skip_ws();
  int c = peek_raw();
  if (c == 'n' || c == 't' || c == 'f') {
    char word[6] = {0};
    int i = 0;
    while (i < 5 && ((c = peek_raw()) >= 'a' && c <= 'z')) word[i++] = static_cast<char>(get());
    if (std::strcmp(word, "null") == 0) {
      v = std::numeric_limits<double>::quiet_NaN();
    } else if (std::strcmp(word, "true") == 0) {
      v = 1;
    } else if (std::strcmp(word, "false") == 0) {
      v = 0;
    } else {
      return fail("bad literal");
    }
    return after_value();
  }
  bool neg = false;
  if (c == '-') {
    neg = true;
    ++pos_;
  } else if (c == '+') {
    ++pos_;
  }
  // NaN / Infinity as Python's json writes them.
  c = peek_raw();
  if (c == 'N' || c == 'I') {
    char word[10] = {0};
    int i = 0;
    while (i < 8 && (((c = peek_raw()) >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'))) word[i++] = static_cast<char>(get());
    if (std::strcmp(word, "NaN") == 0) {
      v = std::numeric_limits<double>::quiet_NaN();
    } else if (std::strcmp(word, "Infinity") == 0) {
      v = neg ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
    } else {
      return fail("bad literal");
    }
    return after_value();
  }
  std::uint64_t mant = 0;
  int digits = 0, exp10 = 0;
  bool any = false;
  while ((c = peek_raw()) >= '0' && c <= '9') {
    ++pos_;
    any = true;
    if (digits < 19) {
      mant = mant * 10u + static_cast<unsigned>(c - '0');
      if (mant != 0) ++digits;
    } else {
      ++exp10;
    }
  }
  if (peek_raw() == '.') {
    ++pos_;
    while ((c = peek_raw()) >= '0' && c <= '9') {
      ++pos_;
      any = true;
      if (digits < 19) {
        mant = mant * 10u + static_cast<unsigned>(c - '0');
        if (mant != 0) ++digits;
        --exp10;
      }
    }
  }
  if (!any) return fail("expected a number");
  c = peek_raw();
  if (c == 'e' || c == 'E') {
    ++pos_;
    bool eneg = false;
    c = peek_raw();
    if (c == '-' || c == '+') {
      eneg = c == '-';
      ++pos_;
    }
    int e = 0;
    while ((c = peek_raw()) >= '0' && c <= '9') {
      ++pos_;
      if (e < 10000) e = e * 10 + (c - '0');
    }
    exp10 += eneg ? -e : e;
  }
  static const double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                  1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  double r = static_cast<double>(mant);  // exact while mant < 2^53 (always for <= 15 digits)
  if (mant == 0) {
    r = 0;
  } else if (exp10 >= 0 && exp10 <= 22) {
    r *= kPow10[exp10];
  } else if (exp10 < 0 && exp10 >= -22) {
    r /= kPow10[-exp10];  // one correctly rounded division
  } else {
    int e = exp10;
    while (e > 22) {
      r *= 1e22;
      e -= 22;
    }
    while (e < -22) {
      r /= 1e22;
      e += 22;
    }
    r = e >= 0 ? r * kPow10[e] : r / kPow10[-e];
  }
  v = neg ? -r : r;
  return after_value();
}

bool JsonReader::read_float(float& v) {
  double d = 0;
  if (!read_double(d)) return false;
  v = static_cast<float>(d);
  return true;
}

bool JsonReader::read_int(int& v) {
  double d = 0;
  if (!read_double(d)) return false;
  v = static_cast<int>(d);
  return true;
}

bool JsonReader::read_bool(bool& v) {
  double d = 0;
  if (!read_double(d)) return false;
  v = d != 0;
  return true;
}

template <typename T>
int JsonReader::read_numbers_impl(T* out, int max) {
  if (!begin_array()) return -1;
  int n = 0;
  while (next_element()) {
    if (peek() == '[') {
      const int m = read_numbers_impl(out == nullptr ? nullptr : out + (n < max ? n : max), n < max ? max - n : 0);
      if (m < 0) return -1;
      n += m;
    } else {
      double d = 0;
      if (!read_double(d)) return -1;
      if (out != nullptr && n < max) out[n] = static_cast<T>(d);
      ++n;
    }
  }
  return ok() ? n : -1;
}

int JsonReader::read_numbers(float* out, int max) { return read_numbers_impl(out, max); }
int JsonReader::read_numbers(double* out, int max) { return read_numbers_impl(out, max); }

bool JsonReader::skip_value() {
  if (!ok()) return false;
  const char c = peek();
  if (c == '{') {
    begin_object();
    char k[8];
    while (next_key(k, sizeof(k))) {
      if (!skip_value()) return false;
    }
    return ok();
  }
  if (c == '[') {
    begin_array();
    while (next_element()) {
      if (!skip_value()) return false;
    }
    return ok();
  }
  if (c == '"') return read_string(nullptr, 0);
  double d;
  return read_double(d);
}

}  // namespace ktest
