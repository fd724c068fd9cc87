// The streaming JSON reader the golden tests use on both targets, checked against the reference
// files themselves.
#include "json_pull.hpp"

#include <cmath>
#include <cstring>

#include "ktest.hpp"
#include "test_io.hpp"

KTEST(JsonPull, ReadsGoldenAllocationMatrixBitExactly) {
  ktest::JsonReader r;
  KASSERT_TRUE(r.open(ktest::golden_path("allocation.json")));
  KASSERT_TRUE(r.begin_object());
  KASSERT_TRUE(r.find_key("robots"));
  KASSERT_TRUE(r.begin_object());
  KASSERT_TRUE(r.find_key("base_quadrotor"));
  KASSERT_TRUE(r.begin_object());
  KASSERT_TRUE(r.find_key("num_motors"));
  int n = 0;
  KASSERT_TRUE(r.read_int(n));
  KEXPECT_EQ(n, 4);
  KASSERT_TRUE(r.find_key("allocation_matrix_A"));
  float a[24];
  KEXPECT_EQ(r.read_numbers(a, 24), 24);
  // Row 3 (tx) starts with -0.129999995, the float32 nearest to -0.13.
  KEXPECT_EQ(a[12], -0.13f);
  KEXPECT_EQ(a[8], 1.0f);
  KEXPECT_TRUE(r.ok());
}

KTEST(JsonPull, MissingFileIsAnErrorNotACrash) {
  ktest::JsonReader r;
  KEXPECT_FALSE(r.open("/nonexistent/kestrel.json"));
  KEXPECT_FALSE(r.ok());
  KEXPECT_FALSE(r.begin_object());
}
