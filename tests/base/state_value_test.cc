#include "gipsi/base/state_value.h"

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/base/object_state.h"
#include "haptics/no_allocation_guard.h"

namespace gipsi {
namespace {

enum class Mode : std::uint8_t { kA, kB };

struct Inner {
  double p = 0;
  std::vector<int> ids;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("p", s.p);
    v("ids", s.ids);
  }
};

/// One field of every supported kind.
struct Sample {
  double t = 0;
  std::int64_t count = 0;
  bool flag = false;
  Mode mode = Mode::kA;
  std::string label;
  VecX x;
  Points points = Points(3, 0);
  Mat3 fixed = Mat3::Zero();
  std::vector<double> history;
  std::array<double, 3> triple{};
  std::vector<Mat3> axes;
  Inner inner;
  std::vector<Inner> many;
  double derived = 0;  // not a field: CopyFields leaves it alone

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("t", s.t);
    v("count", s.count);
    v("flag", s.flag);
    v("mode", s.mode, Shape::kFixed);
    v("label", s.label);
    v("x", s.x, Shape::kFixed);
    v("points", s.points, Shape::kFixed);
    v("fixed", s.fixed);
    v("history", s.history);
    v("triple", s.triple, Shape::kFixed);
    v("axes", s.axes);
    v("inner", s.inner);
    v("many", s.many);
  }
};

Sample MakeSample() {
  Sample s;
  s.t = 0.125;
  s.count = -7;
  s.flag = true;
  s.mode = Mode::kB;
  s.label = "wall";
  s.x = VecX::LinSpaced(5, 0, 1);
  s.points = Points::Constant(3, 4, 0.5);
  s.points(2, 3) = -1;
  s.fixed << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  s.history = {1, 2, 3};
  s.triple = {4, 5, 6};
  s.axes = {Mat3::Identity(), 2 * Mat3::Identity()};
  s.inner = {2.5, {1, 2}};
  s.many = {{1, {}}, {2, {3, 4, 5}}};
  s.derived = 99;
  return s;
}

TEST(StateValue, WriteThenReadRestoresEveryFieldBitwise) {
  const Sample saved = MakeSample();
  StateWriter out;
  WriteFields(out, saved);

  Sample read;  // same scene shapes, other values
  read.mode = Mode::kB;
  read.x = VecX::Zero(5);
  read.points = Points::Zero(3, 4);
  StateReader in(out.TakeBytes(), "test");
  ReadFields(in, read);
  EXPECT_TRUE(in.at_end());
  EXPECT_EQ(FirstDifference(saved, read), "");
  EXPECT_EQ(read.derived, 0);  // not a field
}

TEST(StateValue, FirstDifferenceNamesTheFieldAndIndex) {
  const Sample a = MakeSample();
  Sample b = MakeSample();
  EXPECT_EQ(FirstDifference(a, b), "");
  b.points(1, 2) = std::nextafter(b.points(1, 2), 1.0);  // one bit
  EXPECT_EQ(FirstDifference(a, b), "points[7]");         // column-major: 1 + 3·2
  b = MakeSample();
  b.many[1].ids[2] = 0;
  EXPECT_EQ(FirstDifference(a, b), "many[1].ids[2]");
  b = MakeSample();
  b.history.push_back(4);
  EXPECT_EQ(FirstDifference(a, b), "history (size 3 against 4)");
}

TEST(StateValue, ComparesBitsNotValues) {
  Sample a, b;
  a.t = 0.0;
  b.t = -0.0;  // equal as doubles, different bits
  EXPECT_EQ(FirstDifference(a, b), "t");
  a.t = b.t = std::numeric_limits<double>::quiet_NaN();  // same bits: equal
  EXPECT_EQ(FirstDifference(a, b), "");
}

TEST(StateValue, CopyFieldsCopiesFieldsOnlyAndAllocatesNothingForEqualShapes) {
  const Sample from = MakeSample();
  Sample to = MakeSample();
  to.x.setZero();
  to.points.setZero();
  to.axes[1].setZero();
  to.many[1].ids = {0, 0, 0};
  to.derived = -1;
  {
    testing::NoAllocationGuard guard;
    CopyFields(to, from);
  }
  EXPECT_EQ(FirstDifference(from, to), "");
  EXPECT_EQ(to.derived, -1);
}

TEST(StateValue, ReadingAStateOfAnotherShapeNamesTheField) {
  const Sample saved = MakeSample();
  StateWriter out;
  WriteFields(out, saved);
  Sample other = MakeSample();
  other.x = VecX::Zero(6);  // the scene has one more node
  StateReader in(out.bytes(), "cp.bin");
  try {
    ReadFields(in, other);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(
        e.what(),
        "cp.bin: x is 5 by 1 in the checkpoint but 6 by 1 in this scene; the checkpoint was "
        "written for another scene");
  }
  Sample mode = MakeSample();
  mode.mode = Mode::kA;  // a fixed scalar that differs
  StateReader again(out.bytes(), "cp.bin");
  try {
    ReadFields(again, mode);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "cp.bin: mode is 1 in the checkpoint but 0 in this scene");
  }
}

TEST(StateValue, AnEmptyMatrixMayBeTheLastEntry) {
  // 3 by 0 (a network without elements has no fibres): no values, whatever its row count.
  StateWriter out;
  out.WriteMatrix(Points(3, 0));
  StateReader in(out.TakeBytes(), "test");
  Points none(3, 0);
  in.ReadMatrixExact(none, "the fibres");
  EXPECT_TRUE(in.at_end());
}

TEST(StateValue, BoxesCopyAndCompareThroughTheBase) {
  StateBox<Sample> a(MakeSample());
  StateBox<Sample> b(Sample{});
  ObjectState& base = b;
  EXPECT_NE(base.FirstDifference(a), "");
  base.Assign(a);
  EXPECT_EQ(base.FirstDifference(a), "");

  ByteState bytes_a, bytes_b;
  bytes_a.bytes = "abcd";
  bytes_b.bytes = "abXd";
  EXPECT_EQ(bytes_a.FirstDifference(bytes_b), "the serialised state at byte 2");
  bytes_b.Assign(bytes_a);
  EXPECT_EQ(bytes_a.FirstDifference(bytes_b), "");
}

struct Unbounded {
  VecX v;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("v", s.v);
  }
};

/// The same field with inline storage for at most 4 values.
struct Bounded {
  Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 4, 1> v;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("v", s.v);
  }
};

TEST(StateValue, AMatrixWithInlineStorageRefusesASizeItCannotHold) {
  Unbounded small{VecX::LinSpaced(3, 1, 3)}, big{VecX::Zero(6)};
  StateWriter fits, too_big;
  WriteFields(fits, small);
  WriteFields(too_big, big);
  Bounded read;
  StateReader ok(fits.TakeBytes(), "fits.gck");
  ReadFields(ok, read);
  ASSERT_EQ(read.v.size(), 3);
  EXPECT_EQ(read.v[2], 3.0);
  StateReader bad(too_big.TakeBytes(), "big.gck");
  try {
    ReadFields(bad, read);
    FAIL() << "6 values were read into storage for 4";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("v is 6 by 1 in the checkpoint, more than its storage "
                                         "holds (4 by 1)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(read.v.size(), 3);
}

// Two shares of one problem (another rank's checkpoint: the same entries, arrays of other
// lengths): a position taken in one finds the same entry in the other.
std::string Share(int nodes, double marker) {
  StateWriter out;
  out.WriteString("kernel");
  out.BeginSection("Objects", 3);
  out.WriteInt(2);
  out.BeginSection("First", 1);
  out.WriteArray(std::vector<double>(static_cast<std::size_t>(nodes), 1.0));
  out.WriteMatrix(Points::Ones(3, nodes));
  out.EndSection();
  out.WriteString(std::string(static_cast<std::size_t>(nodes), 'x'));
  out.BeginSection("Second", 2);
  out.WriteDouble(0.5);
  out.BeginSection("Part", 1);
  out.WriteDouble(marker);
  out.WriteArray(std::vector<int>(static_cast<std::size_t>(nodes), 7));
  out.EndSection();
  out.WriteInt(9);
  out.EndSection();
  out.EndSection();
  return out.TakeBytes();
}

TEST(StateReader, APositionFindsTheSameEntryInAnotherShare) {
  StateReader mine(Share(3, 1.0), "p0.gck");
  (void)mine.ReadString();
  mine.BeginSection("Objects", 3);
  (void)mine.ReadInt();
  mine.BeginSection("First", 1);
  mine.SkipRestOfSection();
  mine.EndSection();
  (void)mine.ReadString();
  mine.BeginSection("Second", 2);
  (void)mine.ReadDouble();
  const StateReader::Position at = mine.position();
  ASSERT_EQ(at.index, (std::vector<std::uint64_t>{1, 3, 1}));
  ASSERT_EQ(at.tags, (std::vector<std::string>{"Objects", "Second"}));

  StateReader other(Share(1000, 2.0), "p1.gck");
  other.Seek(at);
  other.BeginSection("Part", 1);
  EXPECT_EQ(other.ReadDouble(), 2.0);
  std::vector<int> ids;
  other.ReadArray(ids);
  EXPECT_EQ(ids.size(), 1000U);
  other.EndSection();
  EXPECT_EQ(other.ReadInt(), 9);
  EXPECT_EQ(other.position().index, (std::vector<std::uint64_t>{1, 3, 3}));
}

// NextIsSection tells a section by its tag without reading it; SkipEntries passes entries of
// any kind (a whole section counts as one).
TEST(StateReader, TheNextSectionIsToldWithoutReadingIt) {
  StateReader in(Share(3, 1.0), "p0.gck");
  EXPECT_FALSE(in.NextIsSection("Objects"));  // a string first
  (void)in.ReadString();
  EXPECT_TRUE(in.NextIsSection("Objects"));
  EXPECT_FALSE(in.NextIsSection("Object"));
  EXPECT_FALSE(in.NextIsSection("Objects2"));
  in.BeginSection("Objects", 3);
  EXPECT_FALSE(in.NextIsSection("First"));  // an integer first
  in.SkipEntries(1);
  EXPECT_TRUE(in.NextIsSection("First"));
  in.SkipEntries(2);  // the section "First" and the string after it
  EXPECT_TRUE(in.NextIsSection("Second"));
  in.SkipEntries(1);
  EXPECT_FALSE(in.NextIsSection("Second"));  // the end of "Objects"
  in.EndSection();
}

TEST(StateReader, SeekIntoAnotherLayoutIsRefusedByName) {
  StateReader mine(Share(3, 1.0), "p0.gck");
  (void)mine.ReadString();
  mine.BeginSection("Objects", 3);
  const StateReader::Position at = mine.position();
  StateWriter other_layout;
  other_layout.WriteString("kernel");
  other_layout.BeginSection("Scene", 3);
  other_layout.EndSection();
  StateReader other(other_layout.TakeBytes(), "p1.gck");
  try {
    other.Seek(at);
    FAIL() << "a position found in another layout";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("p1.gck: expected state of 'Objects' but the checkpoint "
                                         "has 'Scene' here"),
              std::string::npos)
        << e.what();
  }
  StateWriter short_one;
  short_one.WriteString("kernel");
  StateReader truncated(short_one.TakeBytes(), "p2.gck");
  EXPECT_THROW(truncated.Seek(at), InputError);
}

}  // namespace
}  // namespace gipsi
