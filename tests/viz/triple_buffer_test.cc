#include "gipsi/viz/triple_buffer.h"

#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace gipsi::viz {
namespace {

TEST(TripleBuffer, ReaderSeesOnlyTheNewestPublishedValue) {
  TripleBuffer<int> buffer;
  EXPECT_FALSE(buffer.Acquire());  // nothing published yet
  buffer.back() = 1;
  buffer.Publish();
  buffer.back() = 2;
  buffer.Publish();
  buffer.back() = 3;  // written, not published
  ASSERT_TRUE(buffer.Acquire());
  EXPECT_EQ(buffer.front(), 2);
  EXPECT_FALSE(buffer.Acquire());  // nothing new: front stays
  EXPECT_EQ(buffer.front(), 2);
  buffer.Publish();
  ASSERT_TRUE(buffer.Acquire());
  EXPECT_EQ(buffer.front(), 3);
}

TEST(TripleBuffer, WriterNeverWritesTheSlotTheReaderHolds) {
  TripleBuffer<int> buffer;
  buffer.back() = 7;
  buffer.Publish();
  ASSERT_TRUE(buffer.Acquire());
  const int* held = &buffer.front();
  for (int i = 0; i < 10; ++i) {
    EXPECT_NE(&buffer.back(), held);
    buffer.back() = 100 + i;
    buffer.Publish();
  }
  EXPECT_EQ(*held, 7);
}

/// A writer thread publishes frames whose every element equals the frame number; the reader
/// must never see a torn frame (mixed numbers) or a frame older than one it has seen.
TEST(TripleBuffer, ConcurrentReaderNeverSeesTornOrOlderFrames) {
  TripleBuffer<std::vector<long>> buffer;
  for (auto& slot : buffer.slots()) slot.assign(4096, -1);
  constexpr long kFrames = 20000;
  std::thread writer([&] {
    for (long f = 0; f < kFrames; ++f) {
      for (long& x : buffer.back()) x = f;
      buffer.Publish();
    }
  });
  long last = -1, torn = 0, older = 0, seen = 0;
  while (last < kFrames - 1) {
    if (!buffer.Acquire()) {
      std::this_thread::yield();
      continue;
    }
    const auto& frame = buffer.front();
    for (long x : frame) torn += x != frame[0];
    older += frame[0] <= last;
    last = frame[0];
    ++seen;
  }
  writer.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(older, 0);
  EXPECT_GE(seen, 1);
  EXPECT_EQ(last, kFrames - 1);
}

}  // namespace
}  // namespace gipsi::viz
