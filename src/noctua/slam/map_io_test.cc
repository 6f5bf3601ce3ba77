// Maps that outlive a run: a map saved after real tracking loads back byte for byte, a run
// localises every frame in it without changing it or continues mapping from it, and every file
// that is not such a map (missing, foreign, another version, cut, damaged, made with another
// method or camera) is refused with an Error naming the file.
#include "noctua/slam/map_io.h"

#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <random>
#include <string>

#include "noctua/eval/slam_run.h"
#include "noctua/eval/trajectory_error.h"
#include "noctua/pipeline/method.h"
#include "noctua/pipeline/method_config.h"
#include "noctua/slam/rgbd_slam.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

std::filesystem::path Config() {
  return std::filesystem::path(NOCTUA_SOURCE_DIR) / "config/tum_fr1.yaml";
}

std::filesystem::path Fr1() { return testing::DataDir() / "tum_fr1_rpy_200"; }

// The settings file's, optionally with the rolling shutter left uncorrected.
SlamSetup Setup(bool global_shutter) {
  SlamSetup setup = LoadSlamSetup(Config());
  if (global_shutter) setup.options.rolling_shutter_s = 0.0;
  return setup;
}

// A SLAM with the settings file's camera and extractor, as `noctua slam` makes it.
struct Session {
  explicit Session(const std::string& method_name, bool global_shutter = false)
      : setup(Setup(global_shutter)),
        method(pipeline::CreateMethod(method_name, pipeline::LoadMethodConfig(Config()))),
        slam(setup.camera.Camera(), method->feature2d(), setup.options),
        identity(MakeMapIdentity(method_name, setup.camera.Camera(), setup.options)) {}

  SequenceRun Run(const io::Sequence& sequence, int frames) {
    RunOptions options;
    options.max_frames = frames;
    return RunSequence(slam, sequence, setup.camera.depth_factor, options);
  }
  std::string Bytes() const { return SerializeMap(slam.tracker().map(), identity); }

  SlamSetup setup;
  std::unique_ptr<pipeline::FeatureMethod> method;
  RgbdSlam slam;
  MapIdentity identity;
};

constexpr int kFrames = 60;

// One orb map of the first kFrames frames, made once for all tests.
class MapIoTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sequence_ = std::make_unique<io::Sequence>(io::Sequence::Open(Fr1()));
    Session session("orb");
    const SequenceRun run = session.Run(*sequence_, kFrames);
    ASSERT_EQ(run.trajectory.size(), static_cast<std::size_t>(kFrames));
    bytes_ = new std::string(session.Bytes());
    keyframes_ = session.slam.tracker().map().NumKeyFrames();
    points_ = session.slam.tracker().map().NumMapPoints();
    identity_ = new MapIdentity(session.identity);
  }
  static void TearDownTestSuite() {
    delete bytes_;
    delete identity_;
    sequence_.reset();
  }

  std::filesystem::path WriteFile(const std::string& name, const std::string& bytes) const {
    const auto dir = std::filesystem::path(::testing::TempDir()) / "map_io_test";
    std::filesystem::create_directories(dir);
    const auto path = dir / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }

  // The message of the Error that loading `bytes` from a file called `name` throws.
  std::string Refusal(const std::string& name, const std::string& bytes,
                      const MapIdentity& expected) const {
    const auto path = WriteFile(name, bytes);
    try {
      LoadMap(path, expected);
    } catch (const Error& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(path.string()), std::string::npos) << message;
      return message;
    }
    ADD_FAILURE() << name << " was not refused";
    return "";
  }

  static std::unique_ptr<io::Sequence> sequence_;
  static std::string* bytes_;
  static MapIdentity* identity_;
  static int keyframes_;
  static int points_;
};

std::unique_ptr<io::Sequence> MapIoTest::sequence_;
std::string* MapIoTest::bytes_ = nullptr;
MapIdentity* MapIoTest::identity_ = nullptr;
int MapIoTest::keyframes_ = 0;
int MapIoTest::points_ = 0;

TEST_F(MapIoTest, LoadsBackByteForByte) {
  ASSERT_GE(keyframes_, 3);
  ASSERT_GE(points_, 1000);
  const Map map = ParseMap(*bytes_, *identity_, "map");
  EXPECT_EQ(map.NumKeyFrames(), keyframes_);
  EXPECT_EQ(map.NumMapPoints(), points_);
  EXPECT_EQ(SerializeMap(map, *identity_), *bytes_);
}

TEST_F(MapIoTest, LocalisesEveryFrameWithoutChangingTheMap) {
  Session session("orb");
  session.slam.UseMap(ParseMap(*bytes_, session.identity, "map"), /*localize=*/true);
  const SequenceRun run = session.Run(*sequence_, kFrames);
  ASSERT_EQ(run.frames.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(run.frames[0].method, "relocalisation");
  for (std::size_t i = 0; i < run.frames.size(); ++i) {
    EXPECT_EQ(run.frames[i].state, TrackingState::kOk) << "frame " << i;
    EXPECT_FALSE(run.frames[i].new_keyframe) << "frame " << i;
  }
  const double ate = eval::ComputeAte(sequence_->ground_truth(), run.trajectory).translation_m.rmse;
  EXPECT_LE(ate, 0.02);
  EXPECT_EQ(session.Bytes(), *bytes_);  // nothing added, culled, moved or re-linked
  EXPECT_THROW(session.slam.AdjustWholeMap(10, 0), Error);  // not even on request
}

// Localising in a map that kept few of the points its keyframes saw (culled as new points that
// later keyframes did not confirm, as after a fast turn): the keyframes' own depth readings,
// lifted with their refined poses, hold the frames that those points alone cannot. Map and run
// leave the rolling shutter uncorrected: the frames right after a relocalisation have no
// velocity to undo their shear with, and against corrected keyframes thinned to one point in 8
// frames 1-5 fall short of the inliers a relocalised frame needs (measured: 55 of 60 tracked).
TEST_F(MapIoTest, LocalisesInAThinnedMapFromTheKeyFramesDepth) {
  Session mapping("orb", /*global_shutter=*/true);
  ASSERT_EQ(mapping.Run(*sequence_, kFrames).trajectory.size(), static_cast<std::size_t>(kFrames));
  const int points = mapping.slam.tracker().map().NumMapPoints();
  Session session("orb", /*global_shutter=*/true);
  Map map = ParseMap(mapping.Bytes(), session.identity, "map");
  // One point in 8 kept: too few to hold a frame (7 of the 60 frames were tracked on them alone).
  constexpr int kKeepOneIn = 8;
  for (KeyFrame* keyframe : map.KeyFrames()) {
    for (MapPoint* point : keyframe->map_points()) {
      if (point != nullptr && !point->bad() && point->id() % kKeepOneIn != 0) point->SetBad();
    }
  }
  const int kept = map.NumMapPoints();
  session.slam.UseMap(std::move(map), /*localize=*/true);
  const SequenceRun run = session.Run(*sequence_, kFrames);
  int tracked = 0;
  for (const FrameOutcome& frame : run.frames) tracked += frame.state == TrackingState::kOk;
  const double ate = eval::ComputeAte(sequence_->ground_truth(), run.trajectory).translation_m.rmse;
  EXPECT_LT(kept, points / 4);
  EXPECT_EQ(tracked, kFrames);
  EXPECT_LE(ate, 0.03);  // measured 0.0125 m
  EXPECT_EQ(session.slam.tracker().map().NumMapPoints(), kept);
}

TEST_F(MapIoTest, ContinuesMappingFromALoadedMap) {
  Session first("orb");
  first.Run(*sequence_, 30);
  const int loaded = first.slam.tracker().map().NumKeyFrames();
  Session second("orb");
  second.slam.UseMap(ParseMap(first.Bytes(), second.identity, "map"), /*localize=*/false);
  const SequenceRun run = second.Run(*sequence_, kFrames);
  EXPECT_EQ(run.frames[0].method, "relocalisation");
  EXPECT_EQ(run.trajectory.size(), static_cast<std::size_t>(kFrames));
  // Frames 30-59 see what the loaded map does not: keyframes are added for them.
  int added = 0;
  for (std::size_t i = 30; i < run.frames.size(); ++i) added += run.frames[i].new_keyframe ? 1 : 0;
  EXPECT_GE(added, 1);
  EXPECT_GT(second.slam.tracker().map().all_keyframes().size(), static_cast<std::size_t>(loaded));
  const double ate = eval::ComputeAte(sequence_->ground_truth(), run.trajectory).translation_m.rmse;
  EXPECT_LE(ate, 0.03);
}

TEST_F(MapIoTest, RefusesWhatIsNotAMapOfThisVersionAndRun) {
  const auto has = [](const std::string& message, const std::string& part) {
    return message.find(part) != std::string::npos;
  };
  const std::filesystem::path missing = WriteFile("x", "").parent_path() / "no_such.map";
  try {
    LoadMap(missing, *identity_);
    ADD_FAILURE() << "a missing file was not refused";
  } catch (const Error& error) {
    EXPECT_TRUE(has(error.what(), missing.string()) && has(error.what(), "no such map file"))
        << error.what();
  }
  std::string bytes = *bytes_;
  bytes[0] = 'X';
  EXPECT_TRUE(has(Refusal("magic.map", bytes, *identity_), "not a noctua map"));
  EXPECT_TRUE(has(Refusal("empty.map", "", *identity_), "not a noctua map"));
  bytes = *bytes_;
  bytes[8] = 1;  // format version 1
  EXPECT_TRUE(has(Refusal("version.map", bytes, *identity_), "format version 1"));
  EXPECT_TRUE(has(Refusal("cut.map", bytes_->substr(0, bytes_->size() - 100), *identity_),
                  "truncated map"));
  EXPECT_TRUE(has(Refusal("header.map", bytes_->substr(0, 12), *identity_), "truncated map"));
  bytes = *bytes_;
  bytes[bytes.size() / 2] ^= 0x10;
  EXPECT_TRUE(has(Refusal("flipped.map", bytes, *identity_), "checksum"));
  EXPECT_TRUE(has(Refusal("longer.map", *bytes_ + "x", *identity_), "follow its end"));

  MapIdentity paper = *identity_;
  paper.method = "paper";
  const std::string message = Refusal("orb.map", *bytes_, paper);
  EXPECT_TRUE(has(message, "feature method 'orb'") && has(message, "'paper'")) << message;
  MapIdentity camera = *identity_;
  camera.intrinsics.fx += 1.0;
  EXPECT_TRUE(has(Refusal("camera.map", *bytes_, camera), "camera fx"));
  MapIdentity pyramid = *identity_;
  pyramid.num_levels = 4;
  EXPECT_TRUE(has(Refusal("pyramid.map", *bytes_, pyramid), "pyramid levels"));
  // The map was made with the shipped vocabulary: a run without one, or with another, refuses it.
  ASSERT_EQ(identity_->vocabulary.rfind("k8L4-", 0), 0u) << identity_->vocabulary;
  MapIdentity no_vocabulary = *identity_;
  no_vocabulary.vocabulary = "";
  const std::string without = Refusal("vocabulary.map", *bytes_, no_vocabulary);
  EXPECT_TRUE(has(without, "vocabulary '" + identity_->vocabulary + "'")) << without;
}

// Random cuts and byte flips of a real map are all refused with an Error: by the length and the
// checksum, and, where a flip comes with a matching checksum (a file damaged before it was
// checksummed, or forged), by the parser's own checks, or the map loads, but nothing reads out
// of bounds (AddressSanitizer and UBSan watch this test in the sanitizer build).
TEST_F(MapIoTest, RandomCutsAndFlipsAreRefusedCleanly) {
  std::mt19937 random(19);
  const std::string& map = *bytes_;
  std::uniform_int_distribution<std::size_t> anywhere(0, map.size() - 1);
  std::uniform_int_distribution<int> bit(0, 7);
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t length = anywhere(random);
    EXPECT_THROW(ParseMap(map.substr(0, length), *identity_, "cut"), Error) << length;
  }
  for (int trial = 0; trial < 200; ++trial) {
    std::string bytes = map;
    const std::size_t at = anywhere(random);
    bytes[at] = static_cast<char>(bytes[at] ^ (1 << bit(random)));
    EXPECT_THROW(ParseMap(bytes, *identity_, "flipped"), Error) << at;
  }
  // Flips with the checksum made to match: most in the identity, the counts and the first
  // keyframe's records, where one byte changes the structure, the rest anywhere.
  std::uniform_int_distribution<std::size_t> early(kMapHeaderBytes, kMapHeaderBytes + 1200);
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string bytes = map;
    for (int flips = 1 + trial % 3; flips > 0; --flips) {
      const std::size_t at = trial % 4 == 0 ? anywhere(random) : early(random);
      if (at < kMapHeaderBytes) continue;
      bytes[at] = static_cast<char>(bytes[at] ^ (1 << bit(random)));
    }
    const std::uint32_t crc = Crc32(std::string_view(bytes).substr(kMapHeaderBytes));
    for (int i = 0; i < 4; ++i) {
      bytes[kMapChecksumOffset + i] = static_cast<char>((crc >> (8 * i)) & 0xFF);
    }
    try {
      const Map loaded = ParseMap(bytes, *identity_, "forged");
      EXPECT_GE(loaded.NumKeyFrames(), 1);
    } catch (const Error&) {
      ++refused;
    }
  }
  EXPECT_GE(refused, 50);  // the structural checks do refuse what they see
}

TEST(Crc32Test, KnownValues) {
  EXPECT_EQ(Crc32(""), 0u);
  EXPECT_EQ(Crc32("123456789"), 0xCBF43926u);  // the standard check value
}

// The target through eval::SlamRunner, as `noctua slam --save-map` and then
// `--load-map --localize` run it: every frame localised, as accurately as the map allows, and
// the map unchanged. orb on all 200 frames, which pass over the same places several times (the
// target's run); paper on the first kFrames.
class MapReuseRunTest : public ::testing::TestWithParam<std::string> {
 protected:
  int Frames() const { return GetParam() == "orb" ? 200 : kFrames; }
};

TEST_P(MapReuseRunTest, SavedMapLocalisesEveryFrameOfTheSameCut) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / ("map_reuse_" + GetParam());
  std::filesystem::create_directories(dir);
  eval::SlamRunOptions options;
  options.source.dataset = Fr1();
  options.config = Config();
  options.method = GetParam();
  options.max_frames = Frames();
  options.save_map = dir / "fr1.map";
  // The bounds below compare two runs: both deterministic, or the background bundle
  // adjustment's timing moves the mapping run's error by more than the margin.
  options.deterministic = true;
  const eval::SlamRunReport mapping = eval::RunSlam(options);
  EXPECT_TRUE(mapping.json["map"]["saved"].get<bool>());
  EXPECT_FALSE(mapping.json["map"]["loaded"].get<bool>());

  options.load_map = options.save_map;
  options.localize = true;
  options.save_map = dir / "after_localize.map";
  const eval::SlamRunReport localize = eval::RunSlam(options);
  const nlohmann::json& map = localize.json["map"];
  EXPECT_TRUE(map["loaded"].get<bool>() && map["localize"].get<bool>());
  EXPECT_EQ(map["localised_frames"].get<int>(), Frames());
  EXPECT_EQ(map["loaded_keyframes"].get<int>(), mapping.run.keyframes);
  EXPECT_EQ(localize.run.keyframes, mapping.run.keyframes);
  EXPECT_EQ(localize.run.map_points, mapping.run.map_points);
  ASSERT_TRUE(localize.ate.has_value() && mapping.ate.has_value());
  // As accurate as the map it localises in (orb 0.0177 -> 0.0184 m, the mapping run's frames
  // between keyframes refined, a localising run's not; with ORB-SLAM's local map, which mixes
  // the passes, 0.0221 m; paper 0.0257 -> 0.0206 m)...
  EXPECT_LE(localize.ate->translation_m.rmse, 1.05 * mapping.ate->translation_m.rmse);
  // ...and for orb within issue 19's bar.
  if (GetParam() == "orb") {
    EXPECT_LE(localize.ate->translation_m.rmse, 0.02);
  }
  const auto read = [](const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  EXPECT_EQ(read(dir / "after_localize.map"), read(options.load_map));
}

INSTANTIATE_TEST_SUITE_P(Methods, MapReuseRunTest, ::testing::Values("orb", "paper"));

TEST(MapReuseOptionsTest, RefusesLocalizeWithoutAMapAndASaveIntoAMissingFolder) {
  eval::SlamRunOptions options;
  options.source.dataset = Fr1();
  options.config = Config();
  options.localize = true;
  EXPECT_THROW(options.Check(), Error);
  options.localize = false;
  options.save_map = "/no/such/folder/fr1.map";
  try {
    eval::SlamRunner runner(options);
    ADD_FAILURE() << "a map in a missing folder was not refused";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("/no/such/folder/fr1.map"), std::string::npos);
  }
}

}  // namespace
}  // namespace noctua::slam
