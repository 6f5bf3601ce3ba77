#include "noctua/io/realtime_source.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "noctua/io/openni_camera.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// `count` tiny frames 1/30 s apart, made on demand.
class GeneratedSource : public FrameSource {
 public:
  explicit GeneratedSource(int count) : count_(count) {}
  std::string Describe() const override { return "generated"; }
  std::optional<std::size_t> size() const override { return count_; }
  std::optional<SourceFrame> Next() override {
    if (next_ >= count_) return std::nullopt;
    SourceFrame frame;
    frame.index = next_;
    frame.timestamp = 100.0 + next_ / 30.0;
    frame.images.bgr = cv::Mat(2, 2, CV_8UC3, cv::Scalar::all(next_));
    frame.images.depth_m = cv::Mat(2, 2, CV_32F, cv::Scalar(1.0));
    ++next_;
    return frame;
  }

 private:
  int count_;
  int next_ = 0;
};

TEST(LatestFrameSlotTest, KeepsTheNewestAndRecordsTheFramesItReplaced) {
  LatestFrameSlot slot;
  GeneratedSource frames(4);
  for (int i = 0; i < 3; ++i) slot.Put(*frames.Next());
  EXPECT_EQ(slot.Take()->index, 2);
  slot.Put(*frames.Next());
  slot.Close();
  EXPECT_EQ(slot.Take()->index, 3);
  EXPECT_FALSE(slot.Take().has_value());
  const std::vector<DroppedFrame> dropped = slot.dropped();
  ASSERT_EQ(dropped.size(), 2U);
  EXPECT_EQ(dropped[0].index, 0);
  EXPECT_EQ(dropped[1].index, 1);
  EXPECT_DOUBLE_EQ(dropped[1].timestamp, 100.0 + 1 / 30.0);
}

TEST(LatestFrameSlotTest, HandsOnTheProducersErrorAfterItsFrames) {
  LatestFrameSlot slot;
  GeneratedSource frames(1);
  slot.Put(*frames.Next());
  slot.Close(std::make_exception_ptr(Error("camera gone")));
  EXPECT_TRUE(slot.Take().has_value());
  EXPECT_THROW(slot.Take(), Error);
}

// A reader that takes every frame at once misses none; one that takes a frame and then nothing
// until the end gets that frame and the last one only. Either way, taken + dropped is every frame,
// once each.
TEST(RealTimeSourceTest, EveryFrameIsEitherTakenOrDropped) {
  RealTimeSource fast_reader(std::make_unique<GeneratedSource>(10), 30.0);
  int taken = 0;
  while (fast_reader.Next()) ++taken;
  EXPECT_EQ(taken + static_cast<int>(fast_reader.dropped().size()), 10);

  RealTimeSource late_reader(std::make_unique<GeneratedSource>(10), 100.0);
  // Frames come 0.33 ms apart at 100x 30 Hz: a reader slowed by a loaded machine may get a later
  // frame than 0 first, so the test asks only that nothing is lost or handed out twice.
  const std::optional<SourceFrame> first = late_reader.Next();
  ASSERT_TRUE(first.has_value());
  for (int wait = 0; wait < 1000 && late_reader.dropped().size() < 8; ++wait) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::vector<int> taken_late = {first->index};
  while (const std::optional<SourceFrame> frame = late_reader.Next()) {
    taken_late.push_back(frame->index);
  }
  EXPECT_EQ(taken_late.back(), 9);
  EXPECT_LE(taken_late.size(), 2U);
  std::vector<int> seen = taken_late;
  for (const DroppedFrame& dropped : late_reader.dropped()) seen.push_back(dropped.index);
  std::sort(seen.begin(), seen.end());
  EXPECT_THAT(seen, ElementsAre(0, 1, 2, 3, 4, 5, 6, 7, 8, 9));
}

// The recording starts playing when the reader first asks for a frame, not when the source is
// made: a reader that gets ready slowly (loads a detector) first misses no frame for it.
TEST(RealTimeSourceTest, PlaysFromTheFirstFrameAskedFor) {
  RealTimeSource replay(std::make_unique<GeneratedSource>(3), 1.0);
  // Three frames at 30 Hz take 67 ms to play: over by now, had the clock started. Frames 33 ms
  // apart leave a reader on a loaded machine time to take frame 0 before frame 1 replaces it.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_TRUE(replay.dropped().empty());
  const std::optional<SourceFrame> first = replay.Next();
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->index, 0);
}

// A frame arrives when the recording's clock says, even where loading it took longer (a PNG
// decoded on a busy core): what the SLAM's latency counts from is when a camera would have
// handed it over.
TEST(RealTimeSourceTest, AFrameLoadedLateArrivesWhenItWasDue) {
  class SlowSource : public GeneratedSource {
   public:
    SlowSource() : GeneratedSource(2) {}
    std::optional<SourceFrame> Next() override {
      if (loaded_++ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(60));
      return GeneratedSource::Next();
    }

   private:
    int loaded_ = 0;
  };
  RealTimeSource replay(std::make_unique<SlowSource>(), 1.0);
  const std::optional<SourceFrame> first = replay.Next();
  const std::optional<SourceFrame> second = replay.Next();
  const auto taken = std::chrono::steady_clock::now();
  ASSERT_TRUE(first.has_value() && second.has_value());
  ASSERT_TRUE(first->arrival.has_value() && second->arrival.has_value());
  // Frame 1 takes 60 ms to load, frame 0 is offered at once: frame 1 is taken at least 60 ms
  // after frame 0 arrived, yet arrives 1/30 s after it, as recorded.
  EXPECT_GE(taken - *first->arrival, std::chrono::milliseconds(60));
  const double apart_ms =
      std::chrono::duration<double, std::milli>(*second->arrival - *first->arrival).count();
  EXPECT_NEAR(apart_ms, 1000.0 / 30.0, 0.01);
}

// A source that is never read ends cleanly: its player, holding frame 0 until asked, is stopped.
TEST(RealTimeSourceTest, ASourceNeverReadEndsCleanly) {
  const RealTimeSource unread(std::make_unique<GeneratedSource>(3), 30.0);
  EXPECT_TRUE(unread.dropped().empty());
}

// A frame gets its arrival time when it is offered, not before: what the SLAM's latency counts
// from.
TEST(LatestFrameSlotTest, StampsTheArrivalOfEachFrame) {
  LatestFrameSlot slot;
  GeneratedSource frames(1);
  std::optional<SourceFrame> frame = frames.Next();
  EXPECT_FALSE(frame->arrival.has_value());
  const auto before = std::chrono::steady_clock::now();
  slot.Put(std::move(*frame));
  const std::optional<SourceFrame> taken = slot.Take();
  ASSERT_TRUE(taken->arrival.has_value());
  EXPECT_GE(*taken->arrival, before);
  EXPECT_LE(*taken->arrival, std::chrono::steady_clock::now());
}

// Preloaded: every frame read at once, handed out in order and unchanged, then none; the source it
// read is left at its end.
TEST(PreloadedSourceTest, ReadsEveryFrameFirstThenHandsThemOutInOrder) {
  auto from = std::make_unique<GeneratedSource>(5);
  GeneratedSource* read = from.get();
  PreloadedSource preloaded(std::move(from));
  EXPECT_FALSE(read->Next().has_value());
  EXPECT_EQ(preloaded.size(), 5U);
  EXPECT_EQ(preloaded.Describe(), "generated, preloaded");
  for (int i = 0; i < 5; ++i) {
    const std::optional<SourceFrame> frame = preloaded.Next();
    ASSERT_TRUE(frame.has_value());
    EXPECT_EQ(frame->index, i);
    EXPECT_DOUBLE_EQ(frame->timestamp, 100.0 + i / 30.0);
    EXPECT_EQ(frame->images.bgr.at<cv::Vec3b>(1, 1)[0], i);
  }
  EXPECT_FALSE(preloaded.Next().has_value());
  RealTimeSource replay(std::make_unique<PreloadedSource>(std::make_unique<GeneratedSource>(4)),
                        30.0);
  int taken = 0;
  while (replay.Next()) ++taken;
  EXPECT_EQ(taken + static_cast<int>(replay.dropped().size()), 4);
  FrameSourceOptions options;
  options.dataset = "anywhere";
  options.replay_preload = true;
  try {
    options.Check();
    ADD_FAILURE() << "preloading without a replay rate was accepted";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("replay_preload needs a replay_rate"));
  }
}

TEST(RealTimeSourceTest, SaysItIsRealTimeWhereItsRecordingIsNot) {
  const RealTimeSource replay(std::make_unique<GeneratedSource>(1), 1.0);
  EXPECT_TRUE(replay.real_time());
  EXPECT_FALSE(GeneratedSource(1).real_time());
}

TEST(RealTimeSourceTest, ARateThatIsNotPositiveIsRefused) {
  EXPECT_THROW(RealTimeSource(std::make_unique<GeneratedSource>(1), 0.0), Error);
}

// There is no camera on a build machine: Open says so instead of failing later.
TEST(OpenNiCameraTest, WithoutACameraOpenSaysThatNoneWasFound) {
  try {
    OpenNiCamera::Open();
    GTEST_SKIP() << "an OpenNI2 camera is connected";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("no OpenNI2 camera found"));
  }
}

}  // namespace
}  // namespace noctua::io
