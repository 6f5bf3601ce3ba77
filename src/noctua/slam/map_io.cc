#include "noctua/slam/map_io.h"

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <unordered_map>
#include <utility>
#include <vector>

#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

constexpr std::uint32_t kNoPoint = 0xFFFFFFFFu;
// Bytes of the smallest record of each kind, so that a count read from a damaged file is refused
// before anything of that size is allocated.
constexpr std::size_t kKeypointBytes = 5 * 4 + 2 * 4 + 4 * 8 + 32 + 4;
constexpr std::size_t kKeyFrameBytes = 8 + 8 + 12 * 8 + 4;
constexpr std::size_t kPointBytes = 3 * 8 + 32 + 3 * 8 + 2 * 8 + 4 + 4;
constexpr std::size_t kPairBytes = 8;

// Little-endian, fixed-width writing into a byte string.
class Writer {
 public:
  void U32(std::uint32_t v) { Bytes(v, 4); }
  void I32(std::int32_t v) { U32(static_cast<std::uint32_t>(v)); }
  void U64(std::uint64_t v) { Bytes(v, 8); }
  void I64(std::int64_t v) { U64(static_cast<std::uint64_t>(v)); }
  void F32(float v) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &v, 4);
    U32(bits);
  }
  void F64(double v) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, 8);
    U64(bits);
  }
  void Raw(const void* data, std::size_t size) {
    out_.append(static_cast<const char*>(data), size);
  }
  void String(const std::string& s) {
    U32(static_cast<std::uint32_t>(s.size()));
    out_ += s;
  }
  void Vector3(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) F64(v[i]);
  }
  // A section: 4-byte tag, 8-byte length, then what `body` writes.
  template <typename Body>
  void Section(const char (&tag)[5], Body body) {
    out_.append(tag, 4);
    const std::size_t length_at = out_.size();
    U64(0);
    body();
    const std::uint64_t length = out_.size() - length_at - 8;
    for (int i = 0; i < 8; ++i) out_[length_at + i] = static_cast<char>((length >> (8 * i)) & 0xFF);
  }
  std::string& bytes() { return out_; }

 private:
  void Bytes(std::uint64_t v, int count) {
    for (int i = 0; i < count; ++i) out_.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  }
  std::string out_;
};

// Reads what Writer wrote, refusing (noctua::Error naming the file) anything out of bounds.
class Reader {
 public:
  Reader(std::string_view bytes, std::string name, std::size_t base)
      : bytes_(bytes), name_(std::move(name)), base_(base) {}

  std::uint32_t U32() { return static_cast<std::uint32_t>(Bytes(4)); }
  std::int32_t I32() { return static_cast<std::int32_t>(U32()); }
  std::uint64_t U64() { return Bytes(8); }
  std::int64_t I64() { return static_cast<std::int64_t>(U64()); }
  float F32() {
    const std::uint32_t bits = U32();
    float v = 0.0f;
    std::memcpy(&v, &bits, 4);
    return v;
  }
  double F64() {
    const std::uint64_t bits = U64();
    double v = 0.0;
    std::memcpy(&v, &bits, 8);
    return v;
  }
  std::string_view Raw(std::size_t size) {
    Need(size);
    const std::string_view view = bytes_.substr(offset_, size);
    offset_ += size;
    return view;
  }
  std::string String() { return std::string(Raw(Count(1))); }
  Eigen::Vector3d Vector3() {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = F64();
    return v;
  }
  // A count of records of at least `record_bytes` each, no more than the bytes left can hold.
  std::uint32_t Count(std::size_t record_bytes) {
    const std::uint32_t count = U32();
    if (count > (bytes_.size() - offset_) / record_bytes) Fail("a count exceeds the bytes left");
    return count;
  }
  // The next section, which must carry `tag`, as a reader of its own.
  Reader Section(const char (&tag)[5]) {
    const std::string_view found = Raw(4);
    if (found != std::string_view(tag, 4)) Fail("section " + std::string(tag) + " expected");
    const std::uint64_t length = U64();
    if (length > bytes_.size() - offset_) Fail("section " + std::string(tag) + " is cut short");
    Reader section(bytes_.substr(offset_, length), name_, base_ + offset_);
    offset_ += length;
    return section;
  }
  void ExpectEnd(const std::string& what) const {
    if (offset_ != bytes_.size()) Fail(what + " has bytes it does not use");
  }
  [[noreturn]] void Fail(const std::string& problem) const {
    ThrowFileError(
        name_, "damaged map: " + problem + " (at byte " + std::to_string(base_ + offset_) + ")");
  }

 private:
  void Need(std::size_t size) const {
    if (size > bytes_.size() - offset_) Fail("it ends inside a record");
  }
  std::uint64_t Bytes(int count) {
    Need(static_cast<std::size_t>(count));
    std::uint64_t v = 0;
    for (int i = 0; i < count; ++i) {
      v |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes_[offset_ + i])) << (8 * i);
    }
    offset_ += static_cast<std::size_t>(count);
    return v;
  }

  std::string_view bytes_;
  std::string name_;
  std::size_t base_;  // offset of bytes_ in the file, for messages
  std::size_t offset_ = 0;
};

void WriteIdentity(Writer& w, const MapIdentity& id) {
  w.String(id.method);
  w.String(id.vocabulary);
  w.I32(id.intrinsics.width);
  w.I32(id.intrinsics.height);
  for (double v : {id.intrinsics.fx, id.intrinsics.fy, id.intrinsics.cx, id.intrinsics.cy})
    w.F64(v);
  const geometry::Distortion& d = id.distortion;
  for (double v : {d.k1, d.k2, d.p1, d.p2, d.k3}) w.F64(v);
  w.F64(id.scale_factor);
  w.I32(id.num_levels);
  w.F64(id.bf);
}

MapIdentity ReadIdentity(Reader& r) {
  MapIdentity id;
  id.method = r.String();
  id.vocabulary = r.String();
  id.intrinsics.width = r.I32();
  id.intrinsics.height = r.I32();
  for (double* v : {&id.intrinsics.fx, &id.intrinsics.fy, &id.intrinsics.cx, &id.intrinsics.cy}) {
    *v = r.F64();
  }
  geometry::Distortion& d = id.distortion;
  for (double* v : {&d.k1, &d.k2, &d.p1, &d.p2, &d.k3}) *v = r.F64();
  id.scale_factor = r.F64();
  id.num_levels = r.I32();
  id.bf = r.F64();
  return id;
}

std::string Number(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

// Metres (or pixels) beyond any camera's reach: a value past it is damage, and would overflow
// the integer pixel and grid arithmetic of tracking.
constexpr double kFarthest = 1e6;

bool Bounded(const Eigen::Vector3d& v) {
  return v.allFinite() && v.cwiseAbs().maxCoeff() < kFarthest;
}

}  // namespace

void MapIdentity::CheckSameAs(const MapIdentity& other, const std::filesystem::path& file) const {
  const auto refuse = [&](const std::string& what, const std::string& map_value,
                          const std::string& run_value) {
    ThrowFileError(file, "the map was made with " + what + " " + map_value + ", this run uses " +
                             run_value +
                             "; a map is only reusable with the same features and "
                             "camera");
  };
  if (other.method != method)
    refuse("feature method", "'" + other.method + "'", "'" + method + "'");
  if (other.vocabulary != vocabulary) {
    refuse("vocabulary", "'" + other.vocabulary + "'", "'" + vocabulary + "'");
  }
  const std::array<std::pair<const char*, std::pair<int, int>>, 3> counts = {{
      {"camera width", {other.intrinsics.width, intrinsics.width}},
      {"camera height", {other.intrinsics.height, intrinsics.height}},
      {"pyramid levels", {other.num_levels, num_levels}},
  }};
  for (const auto& [what, values] : counts) {
    if (values.first != values.second) {
      refuse(what, std::to_string(values.first), std::to_string(values.second));
    }
  }
  const std::array<std::pair<const char*, std::pair<double, double>>, 11> fields = {{
      {"camera fx", {other.intrinsics.fx, intrinsics.fx}},
      {"camera fy", {other.intrinsics.fy, intrinsics.fy}},
      {"camera cx", {other.intrinsics.cx, intrinsics.cx}},
      {"camera cy", {other.intrinsics.cy, intrinsics.cy}},
      {"distortion k1", {other.distortion.k1, distortion.k1}},
      {"distortion k2", {other.distortion.k2, distortion.k2}},
      {"distortion p1", {other.distortion.p1, distortion.p1}},
      {"distortion p2", {other.distortion.p2, distortion.p2}},
      {"distortion k3", {other.distortion.k3, distortion.k3}},
      {"pyramid scale factor", {other.scale_factor, scale_factor}},
      {"stereo baseline bf", {other.bf, bf}},
  }};
  for (const auto& [what, values] : fields) {
    // Both come from settings files as decimal text: the same file gives the same doubles.
    if (!(values.first == values.second)) refuse(what, Number(values.first), Number(values.second));
  }
}

MapIdentity MakeMapIdentity(const std::string& method, const geometry::PinholeCamera& camera,
                            const SlamOptions& options) {
  MapIdentity identity;
  identity.method = method;
  identity.intrinsics = camera.intrinsics();
  identity.distortion = camera.distortion();
  identity.scale_factor = options.scale_factor;
  identity.num_levels = options.num_levels;
  identity.bf = options.bf;
  const auto vocabulary = LoadSlamVocabulary(options);
  identity.vocabulary = vocabulary != nullptr ? vocabulary->identity() : "";
  return identity;
}

std::uint32_t Crc32(std::string_view bytes) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t n = 0; n < 256; ++n) {
      std::uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const char byte : bytes) {
    crc = table[(crc ^ static_cast<unsigned char>(byte)) & 0xFFu] ^ (crc >> 8);
  }
  return crc ^ 0xFFFFFFFFu;
}

// Writes and reads the payload's sections; a friend of Map and MapPoint, whose derived fields
// (descriptor, viewing direction, distance range) it keeps as they are.
class MapFile {
 public:
  static std::string Payload(const Map& map, const MapIdentity& identity);
  static Map Parse(Reader& payload, const MapIdentity& expected, const std::string& name);

 private:
  struct Indices {
    std::vector<KeyFrame*> keyframes;
    std::unordered_map<const KeyFrame*, std::uint32_t> keyframe_index;
    std::vector<const MapPoint*> points;
    std::unordered_map<const MapPoint*, std::uint32_t> point_index;
  };
  static Indices Index(const Map& map);
  static void WriteKeyFrame(Writer& w, const KeyFrame& keyframe, const Indices& indices);
  static void WritePoint(Writer& w, const MapPoint& point, const Indices& indices);
  // Reads one keyframe into `map`; its map point slots wait in `slots` for the points.
  static void ReadKeyFrame(Reader& r, const MapIdentity& identity, Map& map,
                           std::vector<std::vector<std::uint32_t>>& slots);
  static void ReadPoint(Reader& r, Map& map, const std::vector<KeyFrame*>& keyframes);
  static void ReadCovisibility(Reader& r, const std::vector<KeyFrame*>& keyframes);
};

MapFile::Indices MapFile::Index(const Map& map) {
  Indices indices;
  indices.keyframes = map.KeyFrames();
  for (std::size_t k = 0; k < indices.keyframes.size(); ++k) {
    indices.keyframe_index[indices.keyframes[k]] = static_cast<std::uint32_t>(k);
  }
  for (const auto& point : map.points_) {
    if (point->bad() || point->id() < 0) continue;
    bool observed = false;
    for (const auto& [keyframe, index] : point->observations()) {
      observed = observed || indices.keyframe_index.count(keyframe) > 0;
    }
    if (!observed) continue;
    indices.point_index[point.get()] = static_cast<std::uint32_t>(indices.points.size());
    indices.points.push_back(point.get());
  }
  return indices;
}

void MapFile::WriteKeyFrame(Writer& w, const KeyFrame& keyframe, const Indices& indices) {
  w.I64(keyframe.frame_id());
  w.F64(keyframe.timestamp());
  const geometry::Pose& pose = keyframe.pose_cw();
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) w.F64(pose.linear()(row, col));
  }
  w.Vector3(pose.translation());
  const FrameFeatures& features = keyframe.features();
  w.U32(static_cast<std::uint32_t>(features.size()));
  for (int i = 0; i < features.size(); ++i) {
    const cv::KeyPoint& k = features.keypoint(i);
    for (float v : {k.pt.x, k.pt.y, k.size, k.angle, k.response}) w.F32(v);
    w.I32(k.octave);
    w.I32(k.class_id);
    w.F64(features.depth(i));
    w.F64(features.right_u(i));
    // As tracking left it: moved to the middle row's time for a rolling shutter.
    w.F64(features.undistorted(i).x());
    w.F64(features.undistorted(i).y());
    w.Raw(features.descriptor(i), 32);
    const auto found = indices.point_index.find(keyframe.map_point(i));
    w.U32(found == indices.point_index.end() ? kNoPoint : found->second);
  }
}

void MapFile::WritePoint(Writer& w, const MapPoint& point, const Indices& indices) {
  w.Vector3(point.position());
  static const std::array<uchar, 32> kNoDescriptor{};
  w.Raw(point.descriptor_.empty() ? kNoDescriptor.data() : point.descriptor(), 32);
  w.Vector3(point.normal_);
  w.F64(point.min_distance_);
  w.F64(point.max_distance_);
  const auto reference = indices.keyframe_index.find(point.reference());
  std::vector<std::pair<std::uint32_t, int>> observations;
  for (const auto& [keyframe, index] : point.observations()) {
    const auto found = indices.keyframe_index.find(keyframe);
    if (found != indices.keyframe_index.end()) observations.emplace_back(found->second, index);
  }
  // A point outlives the keyframe it was made from: its reference then is its first observer.
  w.U32(reference != indices.keyframe_index.end() ? reference->second : observations[0].first);
  w.U32(static_cast<std::uint32_t>(observations.size()));
  for (const auto& [keyframe, index] : observations) {
    w.U32(keyframe);
    w.U32(static_cast<std::uint32_t>(index));
  }
}

std::string MapFile::Payload(const Map& map, const MapIdentity& identity) {
  const Indices indices = Index(map);
  Writer w;
  w.Section("IDNT", [&] { WriteIdentity(w, identity); });
  w.Section("KFRM", [&] {
    w.U32(static_cast<std::uint32_t>(indices.keyframes.size()));
    for (const KeyFrame* keyframe : indices.keyframes) WriteKeyFrame(w, *keyframe, indices);
  });
  w.Section("MPTS", [&] {
    w.U32(static_cast<std::uint32_t>(indices.points.size()));
    for (const MapPoint* point : indices.points) WritePoint(w, *point, indices);
  });
  w.Section("COVI", [&] {
    w.U32(static_cast<std::uint32_t>(indices.keyframes.size()));
    for (const KeyFrame* keyframe : indices.keyframes) {
      std::vector<std::pair<std::uint32_t, int>> links;
      for (const auto& [other, weight] : keyframe->connections()) {
        const auto found = indices.keyframe_index.find(other);
        if (found != indices.keyframe_index.end()) links.emplace_back(found->second, weight);
      }
      w.U32(static_cast<std::uint32_t>(links.size()));
      for (const auto& [other, weight] : links) {
        w.U32(other);
        w.I32(weight);
      }
    }
  });
  return std::move(w.bytes());
}

void MapFile::ReadKeyFrame(Reader& r, const MapIdentity& identity, Map& map,
                           std::vector<std::vector<std::uint32_t>>& slots) {
  const long frame_id = static_cast<long>(r.I64());
  const double timestamp = r.F64();
  geometry::Pose pose = geometry::Pose::Identity();
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) pose.linear()(row, col) = r.F64();
  }
  pose.translation() = r.Vector3();
  const Eigen::Matrix3d rotation = pose.linear();
  if (!std::isfinite(timestamp) || !pose.matrix().allFinite() || !Bounded(pose.translation()) ||
      !(((rotation.transpose() * rotation) - Eigen::Matrix3d::Identity()).norm() < 1e-6) ||
      !(rotation.determinant() > 0.0)) {
    r.Fail("a keyframe's time or pose is not valid");
  }
  const std::uint32_t count = r.Count(kKeypointBytes);
  std::vector<cv::KeyPoint> keypoints(count);
  cv::Mat descriptors(static_cast<int>(count), 32, CV_8U);
  std::vector<double> depth(count), right_u(count);
  std::vector<Eigen::Vector2d> undistorted(count);
  std::vector<std::uint32_t> points(count);
  const double width = identity.intrinsics.width;
  const double height = identity.intrinsics.height;
  for (std::uint32_t i = 0; i < count; ++i) {
    cv::KeyPoint& k = keypoints[i];
    for (float* v : {&k.pt.x, &k.pt.y, &k.size, &k.angle, &k.response}) *v = r.F32();
    k.octave = r.I32();
    k.class_id = r.I32();
    depth[i] = r.F64();
    right_u[i] = r.F64();
    undistorted[i].x() = r.F64();
    undistorted[i].y() = r.F64();
    std::memcpy(descriptors.ptr<uchar>(static_cast<int>(i)), r.Raw(32).data(), 32);
    points[i] = r.U32();
    // Keypoints lie in the image (undistorting anything far outside it need not converge); a
    // pyramid level outside the pyramid would index past it.
    const bool in_image =
        k.pt.x >= -1.0 && k.pt.x <= width + 1.0 && k.pt.y >= -1.0 && k.pt.y <= height + 1.0;
    if (!in_image || !std::isfinite(k.size) || !std::isfinite(k.angle) ||
        !std::isfinite(k.response) || k.octave < 0 || k.octave >= identity.num_levels ||
        !(depth[i] >= 0.0 && depth[i] < kFarthest) || !(std::abs(right_u[i]) < kFarthest) ||
        !(undistorted[i].cwiseAbs().maxCoeff() < kFarthest)) {
      r.Fail("keypoint " + std::to_string(i) + " is not valid");
    }
  }
  const geometry::PinholeCamera camera(identity.intrinsics, identity.distortion);
  Frame frame(
      frame_id, timestamp,
      std::make_shared<const FrameFeatures>(std::move(keypoints), descriptors, std::move(depth),
                                            std::move(right_u), camera, std::move(undistorted)));
  frame.pose_cw = pose;
  map.AddKeyFrame(frame);
  slots.push_back(std::move(points));
}

void MapFile::ReadPoint(Reader& r, Map& map, const std::vector<KeyFrame*>& keyframes) {
  const Eigen::Vector3d position = r.Vector3();
  const std::string_view descriptor = r.Raw(32);
  const Eigen::Vector3d normal = r.Vector3();
  const double min_distance = r.F64();
  const double max_distance = r.F64();
  const std::uint32_t reference = r.U32();
  if (!Bounded(position) || !Bounded(normal) || !(min_distance >= 0.0) ||
      !(max_distance > 0.0 && max_distance < kFarthest) || reference >= keyframes.size()) {
    r.Fail("a map point is not valid");
  }
  const std::uint32_t count = r.Count(kPairBytes);
  if (count == 0) r.Fail("a map point has no observation");
  MapPoint* point = map.AddMapPoint(position, keyframes[reference]);
  point->SetDescriptor(reinterpret_cast<const uchar*>(descriptor.data()));
  point->normal_ = normal;
  point->min_distance_ = min_distance;
  point->max_distance_ = max_distance;
  for (std::uint32_t o = 0; o < count; ++o) {
    const std::uint32_t k = r.U32();
    const std::uint32_t index = r.U32();
    if (k >= keyframes.size() ||
        index >= static_cast<std::uint32_t>(keyframes[k]->features().size()) ||
        point->observations().count(keyframes[k]) > 0) {
      r.Fail("a map point's observation is not valid");
    }
    point->AddObservation(keyframes[k], static_cast<int>(index));
  }
}

void MapFile::ReadCovisibility(Reader& r, const std::vector<KeyFrame*>& keyframes) {
  if (r.Count(4) != keyframes.size()) r.Fail("covisibility is not given for every keyframe");
  for (KeyFrame* keyframe : keyframes) {
    const std::uint32_t links = r.Count(kPairBytes);
    for (std::uint32_t l = 0; l < links; ++l) {
      const std::uint32_t other = r.U32();
      const std::int32_t weight = r.I32();
      if (other >= keyframes.size() || keyframes[other] == keyframe || weight <= 0) {
        r.Fail("a covisibility link is not valid");
      }
      keyframe->AddConnection(keyframes[other], weight);
    }
  }
}

Map MapFile::Parse(Reader& payload, const MapIdentity& expected, const std::string& name) {
  Reader identity_section = payload.Section("IDNT");
  const MapIdentity identity = ReadIdentity(identity_section);
  identity_section.ExpectEnd("section IDNT");
  expected.CheckSameAs(identity, name);

  Map map;
  std::vector<std::vector<std::uint32_t>> slots;
  Reader keyframe_section = payload.Section("KFRM");
  const std::uint32_t keyframe_count = keyframe_section.Count(kKeyFrameBytes);
  if (keyframe_count == 0) keyframe_section.Fail("the map has no keyframe");
  for (std::uint32_t k = 0; k < keyframe_count; ++k) {
    ReadKeyFrame(keyframe_section, identity, map, slots);
  }
  keyframe_section.ExpectEnd("section KFRM");
  const std::vector<KeyFrame*> keyframes = map.KeyFrames();

  Reader point_section = payload.Section("MPTS");
  const std::uint32_t point_count = point_section.Count(kPointBytes);
  for (std::uint32_t p = 0; p < point_count; ++p) ReadPoint(point_section, map, keyframes);
  point_section.ExpectEnd("section MPTS");
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    for (std::size_t i = 0; i < slots[k].size(); ++i) {
      const std::uint32_t p = slots[k][i];
      if (p == kNoPoint) continue;
      if (p >= point_count) keyframe_section.Fail("a keypoint refers to a missing map point");
      keyframes[k]->SetMapPoint(static_cast<int>(i), map.points_[p].get());
    }
  }

  Reader covisibility_section = payload.Section("COVI");
  ReadCovisibility(covisibility_section, keyframes);
  covisibility_section.ExpectEnd("section COVI");
  payload.ExpectEnd("the payload");
  return map;
}

std::string SerializeMap(const Map& map, const MapIdentity& identity) {
  const std::string payload = MapFile::Payload(map, identity);
  Writer header;
  header.Raw(kMapMagic, sizeof(kMapMagic));
  header.U32(kMapFormatVersion);
  header.U64(payload.size());
  header.U32(Crc32(payload));
  return header.bytes() + payload;
}

void SaveMap(const Map& map, const MapIdentity& identity, const std::filesystem::path& path) {
  if (map.NumKeyFrames() == 0) ThrowFileError(path, "no map to save: the SLAM never started one");
  io::WriteTextFileAtomically(path, SerializeMap(map, identity));
}

Map ParseMap(std::string_view bytes, const MapIdentity& expected, const std::string& name) {
  if (bytes.size() < sizeof(kMapMagic) ||
      std::memcmp(bytes.data(), kMapMagic, sizeof(kMapMagic)) != 0) {
    ThrowFileError(name, "not a noctua map (its first bytes are not \"NOCTMAP\")");
  }
  Reader header(bytes.substr(0, std::min(bytes.size(), kMapHeaderBytes)), name, 0);
  header.Raw(sizeof(kMapMagic));
  if (bytes.size() < kMapHeaderBytes)
    ThrowFileError(name, "truncated map: the header is cut short");
  const std::uint32_t version = header.U32();
  if (version != kMapFormatVersion) {
    ThrowFileError(name, "a noctua map of format version " + std::to_string(version) +
                             "; this build reads version " + std::to_string(kMapFormatVersion));
  }
  const std::uint64_t length = header.U64();
  const std::uint32_t checksum = header.U32();
  const std::string_view payload = bytes.substr(kMapHeaderBytes);
  if (payload.size() < length) {
    ThrowFileError(name, "truncated map: " + std::to_string(payload.size()) + " of its " +
                             std::to_string(length) + " bytes are there");
  }
  if (payload.size() > length) {
    ThrowFileError(
        name, "damaged map: " + std::to_string(payload.size() - length) + " bytes follow its end");
  }
  if (Crc32(payload) != checksum) {
    ThrowFileError(name, "damaged map: its checksum (CRC-32) does not match its bytes");
  }
  Reader reader(payload, name, kMapHeaderBytes);
  return MapFile::Parse(reader, expected, name);
}

Map LoadMap(const std::filesystem::path& path, const MapIdentity& expected) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    ThrowFileError(path, std::filesystem::exists(path, error)
                             ? "not a map file (not a regular file)"
                             : "no such map file");
  }
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) ThrowFileError(path, "cannot read the map file");
  return ParseMap(bytes, expected, path.string());
}

}  // namespace noctua::slam
