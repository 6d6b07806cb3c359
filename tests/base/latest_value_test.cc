#include "gipsi/base/latest_value.h"

#include <cstdint>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace gipsi {
namespace {

TEST(LatestValue, ReaderSeesOnlyTheNewestPublishedValue) {
  LatestValue<int> buffer;
  EXPECT_FALSE(buffer.Fetch());  // nothing published yet
  buffer.back() = 1;
  buffer.Publish();
  buffer.back() = 2;
  buffer.Publish();
  buffer.back() = 3;  // written, not published
  ASSERT_TRUE(buffer.Fetch());
  EXPECT_EQ(buffer.front(), 2);
  EXPECT_FALSE(buffer.Fetch());  // nothing new: front stays
  EXPECT_EQ(buffer.front(), 2);
  buffer.Publish();
  ASSERT_TRUE(buffer.Fetch());
  EXPECT_EQ(buffer.front(), 3);
}

TEST(LatestValue, WriterNeverWritesTheSlotTheReaderHolds) {
  LatestValue<int> buffer;
  buffer.back() = 7;
  buffer.Publish();
  ASSERT_TRUE(buffer.Fetch());
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
TEST(LatestValue, ConcurrentReaderNeverSeesTornOrOlderFrames) {
  LatestValue<std::vector<long>> buffer;
  for (int i = 0; i < 3; ++i) buffer.slot(i).assign(4096, -1);
  constexpr long kFrames = 20000;
  std::thread writer([&] {
    for (long f = 0; f < kFrames; ++f) {
      for (long& x : buffer.back()) x = f;
      buffer.Publish();
    }
  });
  long last = -1, torn = 0, older = 0, seen = 0;
  while (last < kFrames - 1) {
    if (!buffer.Fetch()) {
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

struct Stamped {
  std::int64_t a = 0, b = 0, c = 0;
};

TEST(LatestValue, TheConsumerOnlySeesWholeValuesInOrder) {
  LatestValue<Stamped> buffer;
  constexpr std::int64_t kCount = 200000;
  std::thread producer([&] {
    for (std::int64_t k = 1; k <= kCount; ++k) {
      Stamped& s = buffer.back();
      s.a = k;
      s.b = 2 * k;
      s.c = 3 * k;
      buffer.Publish();
    }
  });
  std::int64_t last = 0, fetched = 0;
  while (last < kCount) {
    if (!buffer.Fetch()) continue;
    ++fetched;
    const Stamped& s = buffer.front();
    ASSERT_EQ(s.b, 2 * s.a);
    ASSERT_EQ(s.c, 3 * s.a);
    ASSERT_GT(s.a, last);  // never older than what was already seen
    last = s.a;
  }
  producer.join();
  EXPECT_GT(fetched, 0);
}

}  // namespace
}  // namespace gipsi
