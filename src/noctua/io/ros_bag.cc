#include "noctua/io/ros_bag.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <opencv2/imgproc.hpp>

#include "noctua/util/error.h"

namespace noctua::io {
namespace fs = std::filesystem;
namespace {

using ImagePtr = sensor_msgs::Image::ConstPtr;

// "FILE: topic T, message N: problem", for everything about one message.
[[noreturn]] void ThrowMessageError(const fs::path& path, const TimedFile& message,
                                    const std::string& problem) {
  ThrowFileError(
      path, "topic " + message.file + ", message " + std::to_string(message.line) + ": " + problem);
}

// The rosbag and ROS serialisation libraries throw their own exceptions (rosbag::BagException,
// ros::Exception); they become noctua::Error naming the file.
template <typename F>
auto ReadingBag(const fs::path& path, F&& read) {
  try {
    return read();
  } catch (const Error&) {
    throw;
  } catch (const std::exception& error) {
    ThrowFileError(
        path, std::string("cannot read the bag (truncated, or not a ROS1 bag?): ") + error.what());
  }
}

bool IsColourEncoding(const std::string& encoding) {
  return encoding == "rgb8" || encoding == "bgr8";
}
bool IsDepthEncoding(const std::string& encoding) {
  return encoding == "32FC1" || encoding == "16UC1";
}

// The message's pixels, after checking that its size, step and data agree.
cv::Mat PixelsOf(const fs::path& path, const TimedFile& where, const sensor_msgs::Image& image,
                 int type) {
  const std::size_t row_bytes = image.width * CV_ELEM_SIZE(type);
  if (image.width == 0 || image.height == 0 || image.step < row_bytes ||
      image.data.size() < static_cast<std::size_t>(image.step) * image.height) {
    ThrowMessageError(path, where,
                      "damaged image: " + std::to_string(image.width) + "x" +
                          std::to_string(image.height) + " " + image.encoding + ", step " +
                          std::to_string(image.step) + ", " + std::to_string(image.data.size()) +
                          " bytes of data");
  }
  if (image.is_bigendian && CV_ELEM_SIZE1(type) > 1) {
    ThrowMessageError(path, where, "big-endian " + image.encoding + " is not supported");
  }
  return cv::Mat(static_cast<int>(image.height), static_cast<int>(image.width), type,
                 const_cast<std::uint8_t*>(image.data.data()), image.step);
}

cv::Mat ColourOf(const fs::path& path, const TimedFile& where, const sensor_msgs::Image& image) {
  const cv::Mat pixels = PixelsOf(path, where, image, CV_8UC3);
  cv::Mat bgr;
  if (image.encoding == "rgb8") {
    cv::cvtColor(pixels, bgr, cv::COLOR_RGB2BGR);
  } else {
    bgr = pixels.clone();
  }
  return bgr;
}

// Metres, CV_32F, 0 where there is no measurement (NaN, infinite or not positive in 32FC1).
cv::Mat DepthOf(const fs::path& path, const TimedFile& where, const sensor_msgs::Image& image) {
  cv::Mat metres;
  if (image.encoding == "16UC1") {
    PixelsOf(path, where, image, CV_16UC1).convertTo(metres, CV_32F, 1.0 / 1000.0);
    return metres;
  }
  metres = PixelsOf(path, where, image, CV_32FC1).clone();
  metres.forEach<float>([](float& depth, const int*) {
    if (!std::isfinite(depth) || depth < 0.0F) depth = 0.0F;
  });
  return metres;
}

// Every image message of a topic in bag order, with its header stamp, encoding checked.
struct TopicMessages {
  std::vector<rosbag::MessageInstance> messages;
  std::vector<TimedFile> stamps;
};

}  // namespace

void RosBagOptions::Check() const {
  CheckOption(!rgb_topic.empty(), "rgb_topic must not be empty");
  CheckOption(!depth_topic.empty(), "depth_topic must not be empty");
  CheckOption(rgb_topic != depth_topic, "rgb_topic and depth_topic must differ");
  CheckOption(max_association_dt_s > 0.0, "max_association_dt_s must be positive");
  CheckOption(max_frames >= 0, "max_frames must not be negative");
}

struct RosBagSource::Impl {
  fs::path path;
  RosBagOptions options;
  rosbag::Bag bag;
  std::map<std::string, TopicMessages> topics;  // rgb and depth topic
  std::vector<RgbdPair> pairs;
  std::size_t count = 0;
  std::size_t next = 0;

  void ReadTopics();
  [[noreturn]] void ThrowMissingTopic(const std::string& topic, const std::string& role);
  ImagePtr Read(const TimedFile& message);
};

void RosBagSource::Impl::ThrowMissingTopic(const std::string& topic, const std::string& role) {
  std::string found;
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* connection : all.getConnections()) {
    if (connection->datatype != "sensor_msgs/Image") continue;
    if (found.find(" " + connection->topic + ",") != std::string::npos) continue;
    found += " " + connection->topic + ",";
  }
  if (!found.empty()) found.pop_back();
  ThrowFileError(path, "no sensor_msgs/Image messages on the " + role + " topic " + topic +
                           " (the bag's image topics:" + (found.empty() ? " none" : found) +
                           "; choose with --rgb-topic / --depth-topic)");
}

void RosBagSource::Impl::ReadTopics() {
  for (const auto& [topic, role] :
       {std::pair{options.rgb_topic, "colour"}, std::pair{options.depth_topic, "depth"}}) {
    TopicMessages& found = topics[topic];
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    for (const rosbag::MessageInstance& message : view) {
      const TimedFile where{0.0, topic, static_cast<int>(found.messages.size()) + 1};
      if (message.getDataType() != "sensor_msgs/Image") {
        ThrowMessageError(path, where, "is a " + message.getDataType() + ", not an image");
      }
      const ImagePtr image = message.instantiate<sensor_msgs::Image>();
      const bool colour = topic == options.rgb_topic;
      if (colour ? !IsColourEncoding(image->encoding) : !IsDepthEncoding(image->encoding)) {
        ThrowMessageError(path, where,
                          "unsupported encoding '" + image->encoding + "' (" + role + " must be " +
                              (colour ? "rgb8 or bgr8" : "32FC1 or 16UC1") + ")");
      }
      found.messages.push_back(message);
      found.stamps.push_back({image->header.stamp.toSec(), topic, where.line});
    }
    if (found.messages.empty()) ThrowMissingTopic(topic, role);
  }
}

ImagePtr RosBagSource::Impl::Read(const TimedFile& message) {
  const rosbag::MessageInstance& instance =
      topics.at(message.file).messages.at(static_cast<std::size_t>(message.line - 1));
  return ReadingBag(path, [&] { return instance.instantiate<sensor_msgs::Image>(); });
}

RosBagSource::RosBagSource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RosBagSource::~RosBagSource() = default;

std::unique_ptr<RosBagSource> RosBagSource::Open(const fs::path& path,
                                                 const RosBagOptions& options) {
  options.Check();
  std::error_code error;
  if (!fs::is_regular_file(path, error)) ThrowFileError(path, "no such bag file");
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->options = options;
  ReadingBag(path, [&] {
    impl->bag.open(path.string(), rosbag::bagmode::Read);
    impl->ReadTopics();
  });
  const TopicMessages& rgb = impl->topics.at(options.rgb_topic);
  const TopicMessages& depth = impl->topics.at(options.depth_topic);
  impl->pairs = AssociateByTimestamp(rgb.stamps, depth.stamps, options.max_association_dt_s);
  if (impl->pairs.empty()) {
    ThrowFileError(path, "no colour image has a depth image within " +
                             std::to_string(options.max_association_dt_s) + " s");
  }
  impl->count = options.max_frames > 0
                    ? std::min(impl->pairs.size(), static_cast<std::size_t>(options.max_frames))
                    : impl->pairs.size();
  return std::unique_ptr<RosBagSource>(new RosBagSource(std::move(impl)));
}

std::string RosBagSource::Describe() const { return "bag " + impl_->path.string(); }
std::optional<std::size_t> RosBagSource::size() const { return impl_->count; }
const Trajectory& RosBagSource::ground_truth() const { return impl_->options.ground_truth; }
const std::vector<RgbdPair>& RosBagSource::pairs() const { return impl_->pairs; }

std::optional<SourceFrame> RosBagSource::Next() {
  if (impl_->next >= impl_->count) return std::nullopt;
  const std::size_t index = impl_->next++;
  const RgbdPair& pair = impl_->pairs[index];
  SourceFrame frame;
  frame.index = static_cast<int>(index);
  frame.timestamp = pair.rgb.timestamp;
  frame.images.bgr = ColourOf(impl_->path, pair.rgb, *impl_->Read(pair.rgb));
  frame.images.depth_m = DepthOf(impl_->path, pair.depth, *impl_->Read(pair.depth));
  if (frame.images.depth_m.size() != frame.images.bgr.size()) {
    ThrowMessageError(impl_->path, pair.depth,
                      "depth image is " + std::to_string(frame.images.depth_m.cols) + "x" +
                          std::to_string(frame.images.depth_m.rows) + " but its colour image is " +
                          std::to_string(frame.images.bgr.cols) + "x" +
                          std::to_string(frame.images.bgr.rows));
  }
  return frame;
}

void RosBagWriteOptions::Check() const {
  CheckOption(IsColourEncoding(rgb_encoding), "rgb_encoding must be rgb8 or bgr8");
  CheckOption(IsDepthEncoding(depth_encoding), "depth_encoding must be 32FC1 or 16UC1");
  CheckOption(!rgb_topic.empty() && !depth_topic.empty() && rgb_topic != depth_topic,
              "rgb_topic and depth_topic must be two names");
  CheckOption(max_frames >= 0, "max_frames must not be negative");
}

namespace {

sensor_msgs::Image ImageMessage(const cv::Mat& pixels, const std::string& encoding, double stamp,
                                int seq) {
  sensor_msgs::Image message;
  message.header.seq = static_cast<std::uint32_t>(seq);
  message.header.stamp = ros::Time(stamp);
  message.header.frame_id = "/openni_rgb_optical_frame";
  message.height = static_cast<std::uint32_t>(pixels.rows);
  message.width = static_cast<std::uint32_t>(pixels.cols);
  message.encoding = encoding;
  message.step = static_cast<std::uint32_t>(pixels.cols * pixels.elemSize());
  const cv::Mat continuous = pixels.isContinuous() ? pixels : pixels.clone();
  message.data.assign(continuous.datastart, continuous.dataend);
  return message;
}

cv::Mat DepthPixels(const cv::Mat& metres, const std::string& encoding) {
  cv::Mat pixels;
  if (encoding == "16UC1") {
    metres.convertTo(pixels, CV_16U, 1000.0);
    return pixels;
  }
  pixels = metres.clone();
  pixels.setTo(std::numeric_limits<float>::quiet_NaN(), metres <= 0.0F);  // TUM: NaN = none
  return pixels;
}

}  // namespace

void WriteRosBag(const Sequence& sequence, double depth_factor, const fs::path& path,
                 const RosBagWriteOptions& options) {
  options.Check();
  const std::size_t count =
      options.max_frames > 0
          ? std::min(sequence.size(), static_cast<std::size_t>(options.max_frames))
          : sequence.size();
  rosbag::Bag bag;
  try {
    bag.open(path.string(), rosbag::bagmode::Write);
  } catch (const std::exception& error) {
    ThrowFileError(path, std::string("cannot write the bag: ") + error.what());
  }
  for (std::size_t i = 0; i < count; ++i) {
    const Frame& frame = sequence.frame(i);
    const FrameImages images = sequence.Load(frame, depth_factor);
    cv::Mat colour = images.bgr;
    if (options.rgb_encoding == "rgb8") cv::cvtColor(images.bgr, colour, cv::COLOR_BGR2RGB);
    const int seq = static_cast<int>(i);
    try {
      bag.write(options.rgb_topic, ros::Time(frame.timestamp),
                ImageMessage(colour, options.rgb_encoding, frame.timestamp, seq));
      bag.write(options.depth_topic, ros::Time(frame.depth_timestamp),
                ImageMessage(DepthPixels(images.depth_m, options.depth_encoding),
                             options.depth_encoding, frame.depth_timestamp, seq));
    } catch (const std::exception& error) {
      ThrowFileError(path, std::string("cannot write the bag: ") + error.what());
    }
  }
}

}  // namespace noctua::io
