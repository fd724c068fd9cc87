#include "kestrel/kernel/containers.hpp"

#include "ktest.hpp"

using namespace kestrel;

KTEST(FixedVector, OverflowIsAStatusNotACrash) {
  FixedVector<int, 3> v;
  KEXPECT_TRUE(v.push_back(1) == Status::ok);
  KEXPECT_TRUE(v.push_back(2) == Status::ok);
  KEXPECT_TRUE(v.push_back(3) == Status::ok);
  KEXPECT_TRUE(v.full());
  KEXPECT_TRUE(v.push_back(4) == Status::capacity_exceeded);
  KEXPECT_EQ(v.size(), 3u);
  KEXPECT_EQ(v[2], 3);
  int sum = 0;
  for (int x : v) sum += x;
  KEXPECT_EQ(sum, 6);
  KEXPECT_TRUE(v.resize(5) == Status::capacity_exceeded);
  v.pop_back();
  KEXPECT_EQ(v.size(), 2u);
}

KTEST(RingBuffer, FifoOrderAndOverflow) {
  RingBuffer<int, 3> r;
  int out = 0;
  KEXPECT_TRUE(r.pop(out) == Status::capacity_exceeded);
  for (int i = 0; i < 3; ++i) KEXPECT_TRUE(r.push(i) == Status::ok);
  KEXPECT_TRUE(r.push(9) == Status::capacity_exceeded);
  KEXPECT_TRUE(r.pop(out) == Status::ok);
  KEXPECT_EQ(out, 0);
  KEXPECT_TRUE(r.push(3) == Status::ok);  // wraps around
  KEXPECT_EQ(r.at(0), 1);
  KEXPECT_EQ(r.at(2), 3);
  r.push_overwrite(4);  // drops 1
  KEXPECT_EQ(r.at(0), 2);
  KEXPECT_EQ(r.size(), 3u);
}
