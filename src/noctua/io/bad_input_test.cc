// The bad-input suite of the readers: every damaged file a user may hand noctua is refused with
// an error that names the file (and line) and the problem, or read correctly when it is only
// unusual (grey, RGBA, CRLF, comments). Damaged files are made here from the real data.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "noctua/features/extractor_config.h"
#include "noctua/io/camera_config.h"
#include "noctua/io/dataset.h"
#include "noctua/io/image_file.h"
#include "noctua/io/text_list.h"
#include "noctua/io/trajectory.h"
#include "noctua/io/yaml_file.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

fs::path Fr1Dir() { return testing::DataDir() / "tum_fr1_rpy_200"; }

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

class BadInputTest : public ::testing::Test {
 protected:
  fs::path dir_ =
      fs::temp_directory_path() / ("noctua_bad_input_test_" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir_); }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path Write(const std::string& name, const std::string& bytes) {
    const fs::path path = dir_ / name;
    fs::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  fs::path WriteImage(const std::string& name, const cv::Mat& image) {
    const fs::path path = dir_ / name;
    fs::create_directories(path.parent_path());
    EXPECT_TRUE(cv::imwrite(path.string(), image)) << path;
    return path;
  }
  static std::string ErrorOf(const std::function<void()>& fn) {
    try {
      fn();
    } catch (const Error& error) {
      return error.what();
    }
    return "(no error)";
  }
  static cv::Mat Fr1Rgb() {
    return testing::ReadImageOrThrow(testing::Fr1RgbPaths(1)[0], cv::IMREAD_UNCHANGED);
  }
  // The first `count` associated frames of fr1 as a TUM folder whose lists point at the real
  // images (absolute paths, nothing copied); `edit` may change the association lines.
  fs::path Fr1Subset(const std::string& name, int count,
                     const std::function<void(std::vector<std::string>&)>& edit = {}) {
    std::ifstream in(Fr1Dir() / "associations.txt");
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line) && static_cast<int>(lines.size()) < count;) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      std::string t1, f1, t2, f2;
      fields >> t1 >> f1 >> t2 >> f2;
      lines.push_back(t1 + " " + (Fr1Dir() / f1).string() + " " + t2 + " " +
                      (Fr1Dir() / f2).string());
    }
    if (edit) edit(lines);
    std::string text = "# t_rgb rgb t_depth depth\n";
    for (const auto& line : lines) text += line + "\n";
    Write(name + "/associations.txt", text);
    return dir_ / name;
  }
};

// ---- colour images --------------------------------------------------------------------------

TEST_F(BadInputTest, MissingPngAndJpeg) {
  for (const char* name : {"nope.png", "nope.jpg"}) {
    EXPECT_THAT(ErrorOf([&] { ReadImage8U(dir_ / name); }),
                AllOf(HasSubstr(name), HasSubstr("no such file")));
  }
}

TEST_F(BadInputTest, CorruptPngAndJpeg) {
  // Real file headers followed by garbage: the decoder must fail, not return noise.
  const std::string png = ReadBytes(testing::Fr1RgbPaths(1)[0]);
  std::string corrupt_png = png.substr(0, 64) + std::string(4000, '\x5a');
  std::vector<uchar> jpeg;
  cv::imencode(".jpg", Fr1Rgb(), jpeg);
  std::string corrupt_jpeg(jpeg.begin(), jpeg.begin() + 20);
  corrupt_jpeg += std::string(4000, '\x5a') + "\xFF\xD9";
  for (const auto& file : {std::pair<std::string, std::string>{"c.png", corrupt_png},
                           {"c.jpg", corrupt_jpeg},
                           {"text.png", "this is not an image\n"}}) {
    const fs::path path = Write(file.first, file.second);
    EXPECT_THAT(ErrorOf([&] { ReadImage8U(path); }),
                AllOf(HasSubstr(file.first), HasSubstr("cannot decode")))
        << file.first;
  }
}

TEST_F(BadInputTest, TruncatedPng) {
  const std::string png = ReadBytes(testing::Fr1RgbPaths(1)[0]);
  const fs::path path = Write("half.png", png.substr(0, png.size() / 2));
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(path); }),
              AllOf(HasSubstr("half.png"), HasSubstr("cannot decode")));
}

TEST_F(BadInputTest, TruncatedJpegIsRefusedNotGreyFilled) {
  std::vector<uchar> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", Fr1Rgb(), jpeg));
  const fs::path whole = Write("whole.jpg", std::string(jpeg.begin(), jpeg.end()));
  EXPECT_EQ(ReadImage8U(whole).size(), cv::Size(640, 480));
  const fs::path half =
      Write("half.JPG", std::string(jpeg.begin(), jpeg.begin() + jpeg.size() / 2));
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(half); }),
              AllOf(HasSubstr("half.JPG"), HasSubstr("truncated JPEG")));
}

TEST_F(BadInputTest, EmptyFileAndFolder) {
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(Write("empty.png", "")); }),
              AllOf(HasSubstr("empty.png"), HasSubstr("empty")));
  fs::create_directories(dir_ / "folder.png");
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(dir_ / "folder.png"); }), HasSubstr("is a folder"));
}

TEST_F(BadInputTest, GreyAndRgbaImagesAreReadAndExtracted) {
  cv::Mat grey, rgba;
  cv::cvtColor(Fr1Rgb(), grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(Fr1Rgb(), rgba, cv::COLOR_BGR2BGRA);
  const cv::Mat grey_read = ReadImage8U(WriteImage("grey.png", grey));
  const cv::Mat rgba_read = ReadImage8U(WriteImage("rgba.png", rgba));
  EXPECT_EQ(grey_read.type(), CV_8UC1);
  EXPECT_EQ(rgba_read.type(), CV_8UC4);
  EXPECT_EQ(cv::norm(grey_read, grey, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(rgba_read, rgba, cv::NORM_INF), 0.0);
}

TEST_F(BadInputTest, SixteenBitColourImageIsRefused) {
  cv::Mat wide;
  Fr1Rgb().convertTo(wide, CV_16U, 257.0);
  const fs::path path = WriteImage("wide.png", wide);
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(path); }),
              AllOf(HasSubstr("wide.png"), HasSubstr("expected an 8-bit image, found 16-bit")));
}

TEST_F(BadInputTest, FloatImageIsRefused) {
  cv::Mat real;
  Fr1Rgb().convertTo(real, CV_32F, 1.0 / 255.0);
  const fs::path path = WriteImage("real.tiff", real);
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(path); }),
              AllOf(HasSubstr("real.tiff"), HasSubstr("found 32-bit float")));
}

// ---- depth images ---------------------------------------------------------------------------

TEST_F(BadInputTest, DepthOfTheWrongTypeIsRefused) {
  cv::Mat depth8(480, 640, CV_8UC1, cv::Scalar(40));
  EXPECT_THAT(ErrorOf([&] { ReadDepth16U(WriteImage("d8.png", depth8)); }),
              AllOf(HasSubstr("d8.png"), HasSubstr("found 8-bit with 1 channel")));
  cv::Mat depth3(480, 640, CV_16UC3, cv::Scalar(5000, 5000, 5000));
  EXPECT_THAT(ErrorOf([&] { ReadDepth16U(WriteImage("d3.png", depth3)); }),
              AllOf(HasSubstr("d3.png"), HasSubstr("found 16-bit with 3 channel")));
}

TEST_F(BadInputTest, DepthOfTheWrongSizeIsRefused) {
  const fs::path seq = Fr1Subset("small_depth", 2);
  const Sequence sequence = Sequence::Open(seq);
  cv::Mat depth = ReadDepth16U(sequence.frame(0).depth_path);
  cv::Mat half;
  cv::resize(depth, half, depth.size() / 2, 0, 0, cv::INTER_NEAREST);
  const fs::path small = WriteImage("small.png", half);
  Fr1Subset("small_depth", 2, [&](std::vector<std::string>& lines) {
    lines[0] = lines[0].substr(0, lines[0].rfind(' ') + 1) + small.string();
  });
  const Sequence edited = Sequence::Open(seq);
  EXPECT_THAT(
      ErrorOf([&] { edited.Load(edited.frame(0), 5000.0); }),
      AllOf(HasSubstr("small.png"), HasSubstr("depth image is 320x240"), HasSubstr("640x480")));
  EXPECT_NO_THROW(edited.Load(edited.frame(1), 5000.0));
}

TEST_F(BadInputTest, DepthOfTheWrongScaleIsRefused) {
  const Sequence sequence = Sequence::Open(Fr1Subset("scale", 1));
  // Right factor: fr1 depth lies within a few metres.
  const FrameImages images = sequence.Load(sequence.frame(0), 5000.0);
  EXPECT_LT(cv::mean(images.depth_m, images.depth_m > 0)[0], 10.0);
  // Millimetre factor 1 on TUM data would put the scene kilometres away.
  EXPECT_THAT(ErrorOf([&] { sequence.Load(sequence.frame(0), 1.0); }),
              AllOf(HasSubstr(sequence.frame(0).depth_path.filename().string()),
                    HasSubstr("DepthMapFactor")));
  EXPECT_THAT(ErrorOf([&] { sequence.Load(sequence.frame(0), 0.0); }),
              HasSubstr("depth factor must be positive"));
}

// ---- trajectories ---------------------------------------------------------------------------

TEST_F(BadInputTest, NanAndInfInTrajectories) {
  for (const char* value : {"nan", "NaN", "inf", "-inf"}) {
    const fs::path path =
        Write("t.txt", std::string("1 0 0 0 0 0 0 1\n2 0 ") + value + " 0 0 0 0 1\n");
    EXPECT_THAT(ErrorOf([&] { ReadTumTrajectory(path); }),
                AllOf(HasSubstr("t.txt:2"), HasSubstr("is not a number")))
        << value;
  }
  const fs::path quaternion = Write("q.txt", "1 0 0 0 nan 0 0 1\n");
  EXPECT_THAT(ErrorOf([&] { ReadTumTrajectory(quaternion); }), HasSubstr("q.txt:1"));
}

TEST_F(BadInputTest, NonNormalisedQuaternions) {
  EXPECT_THAT(ErrorOf([&] { ReadTumTrajectory(Write("q2.txt", "1 0 0 0 0 0 0 2\n")); }),
              AllOf(HasSubstr("q2.txt:1"), HasSubstr("not normalised (norm 2.0")));
  EXPECT_THAT(ErrorOf([&] { ReadTumTrajectory(Write("q0.txt", "1 0 0 0 0 0 0 0\n")); }),
              AllOf(HasSubstr("q0.txt:1"), HasSubstr("zero length")));
  // Four-decimal rounding, as in TUM's groundtruth.txt, is accepted and normalised.
  const Trajectory rounded =
      ReadTumTrajectory(Write("q4.txt", "1 0 0 0 0.5774 0.5774 0.5774 0.0001\n"));
  EXPECT_NEAR(Eigen::Quaterniond(rounded.poses()[0].pose.rotation()).norm(), 1.0, 1e-12);
}

TEST_F(BadInputTest, NonMonotonicAndDuplicateTrajectoryTimestamps) {
  EXPECT_THAT(
      ErrorOf([&] { ReadTumTrajectory(Write("back.txt", "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n")); }),
      AllOf(HasSubstr("back.txt:2"), HasSubstr("timestamp does not increase")));
  EXPECT_THAT(
      ErrorOf([&] { ReadTumTrajectory(Write("dup.txt", "1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n")); }),
      AllOf(HasSubstr("dup.txt:2"), HasSubstr("timestamp does not increase")));
}

TEST_F(BadInputTest, EmptyAndCommentOnlyTrajectories) {
  EXPECT_THAT(ErrorOf([&] { ReadTumTrajectory(Write("empty.txt", "")); }),
              AllOf(HasSubstr("empty.txt"), HasSubstr("holds no poses")));
  EXPECT_THAT(ErrorOf([&] { ReadTumTrajectory(Write("c.txt", "# only\n\n  \n# comments\n")); }),
              AllOf(HasSubstr("c.txt"), HasSubstr("holds no poses")));
  EXPECT_EQ(ReadTumTrajectory(Write("one.txt", "1 0 0 0 0 0 0 1\n")).size(), 1u);
}

TEST_F(BadInputTest, CrlfAndCommentLinesReadLikeTheOriginal) {
  const std::string original = ReadBytes(Fr1Dir() / "groundtruth.txt");
  std::string crlf;
  for (char c : original) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  std::string commented;
  std::istringstream lines(original);
  int n = 0;
  for (std::string line; std::getline(lines, line); ++n) {
    commented += line + "\n";
    if (n % 7 == 3) commented += "# a comment in the middle\n\n   \t\n";
  }
  const Trajectory reference = ReadTumTrajectory(Fr1Dir() / "groundtruth.txt");
  for (const auto& path : {Write("crlf.txt", crlf), Write("commented.txt", commented)}) {
    const Trajectory read = ReadTumTrajectory(path);
    ASSERT_EQ(read.size(), reference.size()) << path;
    for (std::size_t i = 0; i < read.size(); ++i) {
      EXPECT_EQ(read.poses()[i].timestamp, reference.poses()[i].timestamp);
      EXPECT_TRUE(read.poses()[i].pose.isApprox(reference.poses()[i].pose, 1e-12));
    }
  }
}

TEST_F(BadInputTest, MalformedTrajectoryLines) {
  EXPECT_THAT(ErrorOf([&] { ReadTumTrajectory(Write("few.txt", "1 0 0 0 0 0 1\n")); }),
              AllOf(HasSubstr("few.txt:1"), HasSubstr("expected 8 fields, found 7")));
  EXPECT_THAT(ErrorOf([&] { ReadTumTrajectory(Write("comma.txt", "1,0,0,0,0,0,0,1\n")); }),
              HasSubstr("comma.txt:1"));
  EXPECT_THAT(ErrorOf([&] { ReadTumTrajectory(dir_ / "absent.txt"); }),
              AllOf(HasSubstr("absent.txt"), HasSubstr("no such file")));
}

// ---- sequences ------------------------------------------------------------------------------

TEST_F(BadInputTest, NonMonotonicAndDuplicateListTimestamps) {
  Write("back/rgb.txt", "2.0 rgb/a.png\n1.0 rgb/b.png\n");
  Write("back/depth.txt", "1.0 depth/a.png\n");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(dir_ / "back"); }),
              AllOf(HasSubstr("rgb.txt:2"), HasSubstr("timestamp does not increase")));
  Write("dup/rgb.txt", "1.0 rgb/a.png\n1.0 rgb/b.png\n");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(dir_ / "dup"); }),
              AllOf(HasSubstr("rgb.txt:2"), HasSubstr("timestamp does not increase")));
  const fs::path swapped = Fr1Subset(
      "swapped", 3, [](std::vector<std::string>& lines) { std::swap(lines[1], lines[2]); });
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(swapped); }),
              AllOf(HasSubstr("associations.txt"), HasSubstr("timestamp does not increase")));
}

TEST_F(BadInputTest, EmptyAndOneFrameSequences) {
  Write("empty/associations.txt", "# nothing here\n");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(dir_ / "empty"); }),
              AllOf(HasSubstr("associations.txt"), HasSubstr("has no frames")));
  Write("empty_lists/rgb.txt", "");
  Write("empty_lists/depth.txt", "");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(dir_ / "empty_lists"); }), HasSubstr("has no frames"));
  const Sequence one = Sequence::Open(Fr1Subset("one", 1));
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one.Load(one.frame(0), 5000.0).bgr.size(), cv::Size(640, 480));
}

TEST_F(BadInputTest, CrlfListsReadLikeTheOriginal) {
  for (const char* name : {"rgb.txt", "depth.txt"}) {
    std::string crlf;
    for (char c : ReadBytes(Fr1Dir() / name))
      crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    Write(std::string("crlf/") + name, crlf);
    const auto original = ReadTimedFileList(Fr1Dir() / name);
    const auto read = ReadTimedFileList(dir_ / "crlf" / name);
    ASSERT_EQ(read.size(), original.size());
    for (std::size_t i = 0; i < read.size(); ++i) {
      EXPECT_EQ(read[i].file, original[i].file);  // no stray '\r' in the file name
      EXPECT_EQ(read[i].timestamp, original[i].timestamp);
    }
  }
}

TEST_F(BadInputTest, ListedImageMissingAndMissingDepthList) {
  Write("nodepth/rgb.txt", "1.0 rgb/a.png\n");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(dir_ / "nodepth"); }),
              AllOf(HasSubstr("depth.txt"), HasSubstr("no such file")));
  const fs::path missing = Fr1Subset("missing", 2, [](std::vector<std::string>& lines) {
    lines[1] = lines[1].substr(0, lines[1].find(' ')) + " rgb/gone.png" +
               lines[1].substr(lines[1].find(' ', lines[1].find(' ') + 1));
  });
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(missing); }),
              AllOf(HasSubstr("associations.txt:3"), HasSubstr("gone.png"),
                    HasSubstr("no such image file")));
}

// ---- settings files -------------------------------------------------------------------------

class YamlWarnings {
 public:
  YamlWarnings() : sink_(std::make_shared<spdlog::sinks::ostream_sink_mt>(text_)) {
    previous_ = spdlog::default_logger();
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("capture", sink_));
  }
  ~YamlWarnings() { spdlog::set_default_logger(previous_); }
  std::string text() const { return text_.str(); }

 private:
  std::ostringstream text_;
  std::shared_ptr<spdlog::sinks::ostream_sink_mt> sink_;
  std::shared_ptr<spdlog::logger> previous_;
};

// config/tum_fr1.yaml without its `extractor:` section (the file's last), which the tests below
// write themselves: YAML refuses a map with the same key twice.
std::string Fr1PresetWithoutExtractorSection() {
  std::string preset = ReadBytes(fs::path(NOCTUA_SOURCE_DIR) / "config/tum_fr1.yaml");
  const std::size_t section = preset.find("\nextractor:");
  if (section != std::string::npos) preset.resize(section + 1);
  return preset;
}

TEST_F(BadInputTest, UnknownYamlKeysAreWarnedAbout) {
  const std::string preset = Fr1PresetWithoutExtractorSection();
  const fs::path path =
      Write("unknown.yaml", preset + "\nextractor:\n  edge_filter: true\n  edge_radus_px: 2\n");
  YamlWarnings warnings;
  const features::ExtractorOptions options = features::LoadExtractorOptions(path);
  EXPECT_TRUE(options.edge_filter.enabled);
  EXPECT_THAT(warnings.text(),
              AllOf(HasSubstr("unknown.yaml"), HasSubstr("edge_radus_px"), HasSubstr("ignored")));
}

TEST_F(BadInputTest, WrongYamlTypesAreRejected) {
  const std::string preset = Fr1PresetWithoutExtractorSection();
  std::string bad_fx = preset;
  bad_fx.replace(bad_fx.find("517.306408"), 10, "five-hundred");
  EXPECT_THAT(ErrorOf([&] { ReadCameraConfig(Write("fx.yaml", bad_fx)); }),
              AllOf(HasSubstr("fx.yaml"), HasSubstr("Camera.fx")));
  std::string bad_features = preset;
  bad_features.replace(bad_features.find("nFeatures: 1000"), 15, "nFeatures: [1, 2]");
  EXPECT_THAT(ErrorOf([&] { features::LoadExtractorOptions(Write("nf.yaml", bad_features)); }),
              AllOf(HasSubstr("nf.yaml"), HasSubstr("ORBextractor.nFeatures")));
  EXPECT_THAT(ErrorOf([&] {
                features::LoadExtractorOptions(
                    Write("flag.yaml", preset + "\nextractor:\n  edge_filter: maybe\n"));
              }),
              AllOf(HasSubstr("flag.yaml"), HasSubstr("edge_filter")));
  EXPECT_THAT(ErrorOf([&] {
                features::LoadExtractorOptions(Write("map.yaml", preset + "\nextractor: 3\n"));
              }),
              AllOf(HasSubstr("map.yaml"), HasSubstr("must be a map")));
}

TEST_F(BadInputTest, BrokenYamlFiles) {
  EXPECT_THAT(ErrorOf([&] { LoadYamlFile(Write("syntax.yaml", "a: 1\nb: [1, 2\nc: 3\n")); }),
              AllOf(HasSubstr("syntax.yaml:"), HasSubstr("invalid YAML")));
  EXPECT_THAT(ErrorOf([&] { LoadYamlFile(Write("list.yaml", "- 1\n- 2\n")); }),
              AllOf(HasSubstr("list.yaml"), HasSubstr("map")));
  EXPECT_THAT(ErrorOf([&] { LoadYamlFile(Write("empty.yaml", "")); }), HasSubstr("empty.yaml"));
  EXPECT_THAT(ErrorOf([&] { ReadCameraConfig(Write("nofx.yaml", "%YAML:1.0\nCamera.fy: 1\n")); }),
              AllOf(HasSubstr("nofx.yaml"), HasSubstr("Camera.fx")));
  const std::string preset = ReadBytes(fs::path(NOCTUA_SOURCE_DIR) / "config/tum_fr1.yaml");
  std::string crlf;
  for (char c : preset) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  EXPECT_DOUBLE_EQ(ReadCameraConfig(Write("crlf.yaml", crlf)).intrinsics.fx, 517.306408);
}

}  // namespace
}  // namespace noctua::io
