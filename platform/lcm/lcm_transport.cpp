// LCM sink and subscriber: pipeline records <-> the generated toposlam_lcm message types.
#include "toposlam/platform/lcm_transport.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "lcm_fragment_monitor.hpp"
#include "place_decode.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/io/image_codec.hpp"
#include "toposlam_lcm/motion_t.hpp"
#include "toposlam_lcm/place_event_t.hpp"
#include "toposlam_lcm/place_t.hpp"
#include "toposlam_lcm/place_v1_t.hpp"
#include "toposlam_lcm/status_t.hpp"
#include "toposlam_lcm/status_v1_t.hpp"
#include "toposlam_lcm/status_v2_t.hpp"
#include "toposlam_lcm/status_v3_t.hpp"
#include "toposlam_lcm/topology_t.hpp"

namespace toposlam {

namespace {

std::int64_t toMicroseconds(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e6)); }

// Encodes `message` into `buffer` (grown once to the largest size seen; no allocation afterwards).
template <typename Message>
int encodeInto(const Message& message, std::vector<std::uint8_t>& buffer) {
  const int size = message.getEncodedSize();
  if (buffer.size() < static_cast<std::size_t>(size)) buffer.resize(static_cast<std::size_t>(size));
  return message.encode(buffer.data(), 0, size);
}

float asFloat(double v) { return static_cast<float>(v); }

}  // namespace

std::int64_t monotonicMicroseconds() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

std::unique_ptr<lcm::LCM> openLcm(const std::string& url) {
  auto instance = std::make_unique<lcm::LCM>(url);
  if (!instance->good())
    throw std::runtime_error("cannot open LCM at '" + url +
                             "': check the URL (e.g. udpm://239.255.76.67:7667?ttl=0) and that the host has a "
                             "multicast route (for loopback only: ip link set lo multicast on; "
                             "ip route add 224.0.0.0/4 dev lo)");
  return instance;
}

std::string effectiveLcmUrl(const std::string& url) {
  if (!url.empty()) return url;
  const char* fallback = std::getenv("LCM_DEFAULT_URL");
  return fallback != nullptr && *fallback != '\0' ? fallback : "udpm://239.255.76.67:7667";
}

std::optional<UdpmAddress> parseUdpmUrl(const std::string& url) {
  const std::string scheme = "udpm://";
  if (url.rfind(scheme, 0) != 0) return std::nullopt;
  UdpmAddress address;
  const std::string rest = url.substr(scheme.size());
  const std::size_t query = rest.find('?');
  const std::string network = rest.substr(0, query);
  const std::size_t colon = network.find(':');
  if (!network.substr(0, colon).empty()) address.group = network.substr(0, colon);
  if (colon != std::string::npos) address.port = std::atoi(network.c_str() + colon + 1);
  // Options: key=value pairs separated by '&'; only the receive buffer's size matters to a listener.
  std::istringstream options(query == std::string::npos ? "" : rest.substr(query + 1));
  for (std::string option; std::getline(options, option, '&');)
    if (option.rfind("recv_buf_size=", 0) == 0) address.recv_buf_size = std::atoi(option.c_str() + 14);
  return address;
}

std::string lcmRouteProblem(const std::string& url) {
  const std::optional<UdpmAddress> address = parseUdpmUrl(url);
  if (!address) return "";
  const std::string& group = address->group;
  sockaddr_in destination{};
  destination.sin_family = AF_INET;
  destination.sin_port = htons(7667);
  if (inet_pton(AF_INET, group.c_str(), &destination.sin_addr) != 1) return "";  // liblcm's own error says it
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return std::string("cannot create a UDP socket: ") + std::strerror(errno);
  const int result = connect(fd, reinterpret_cast<const sockaddr*>(&destination), sizeof destination);
  const int error = errno;
  close(fd);
  if (result == 0) return "";
  return "no route to the multicast group " + group + ": " + std::strerror(error);
}

// --------------------------------------------------------------------------------------------------------

LcmPipelineSink::LcmPipelineSink(const std::string& url, LcmChannels channels, int jpeg_quality,
                                 const MotionStatusCounters* motion)
    : lcm_(openLcm(url)),
      channels_(std::move(channels)),
      jpeg_quality_(jpeg_quality),
      motion_(motion) {
  buffer_.reserve(64 * 1024);
  jpeg_.reserve(32 * 1024);
}

LcmPipelineSink::~LcmPipelineSink() = default;

void LcmPipelineSink::send(const std::string& channel, const void* data, int size) {
  if (size < 0 || lcm_->publish(channel, data, static_cast<unsigned>(size)) != 0) {
    if (failures_++ % 100 == 0) spdlog::warn("lcm: publishing on {} failed ({} failures so far)", channel, failures_);
  }
}

void LcmPipelineSink::publish(const FrameResult& r) {
  const PlaceEstimate& e = r.estimate;
  const std::int64_t now_us = monotonicMicroseconds();

  for (const auto& [place, assignment] : r.finished_places) {
    toposlam_lcm::place_event_t event{};
    event.utime = now_us;
    event.place = assignment.place;
    event.node = assignment.node;
    event.is_new = assignment.is_new;
    event.probability = asFloat(assignment.probability);
    event.first_frame = place.first_frame;
    event.last_frame = place.last_frame;
    event.representative_frame = place.representative_frame;
    event.keypoints = place.keypoints;
    event.thumbnail_width = place.thumbnail.cols;
    event.thumbnail_height = place.thumbnail.rows;
    jpeg_.clear();
    if (!place.thumbnail.empty()) {
      try {
        encodeImage(place.thumbnail, ImageFormat::Jpeg, jpeg_, jpeg_quality_);
      } catch (const ImageCodecError&) {
        jpeg_.clear();  // the event goes out without its picture
      }
    }
    event.jpeg_size = static_cast<std::int32_t>(jpeg_.size());
    event.jpeg.assign(jpeg_.begin(), jpeg_.end());
    event.map_revision = e.map_revision;
    send(channels_.place_event, buffer_.data(), encodeInto(event, buffer_));
  }

  if (r.topology) {
    const TopologySnapshot& t = *r.topology;
    toposlam_lcm::topology_t msg{};
    msg.utime = now_us;
    msg.map_revision = t.map_revision;
    msg.probability = t.probability;
    msg.particles = t.particles;
    msg.current_node = e.node;
    msg.num_nodes = static_cast<std::int32_t>(t.nodes.size());
    // push_back rather than resize(): GCC 12 -O3 reports false null dereferences for resize here.
    msg.nodes.reserve(t.nodes.size());
    for (std::size_t i = 0; i < t.nodes.size(); ++i) {
      toposlam_lcm::topology_node_t n{};
      n.id = t.nodes[i].id;
      n.num_places = static_cast<std::int32_t>(t.nodes[i].places.size());
      n.places = t.nodes[i].places;
      n.num_representatives = static_cast<std::int32_t>(t.nodes[i].representative_frames.size());
      n.representative_frames = t.nodes[i].representative_frames;
      msg.nodes.push_back(std::move(n));
    }
    msg.num_edges = static_cast<std::int32_t>(t.edges.size());
    msg.edges.reserve(t.edges.size());
    for (const TopologyEdge& edge : t.edges) {
      toposlam_lcm::topology_edge_t m{};
      m.from_node = edge.from;
      m.to_node = edge.to;
      m.count = edge.count;
      msg.edges.push_back(m);
    }
    send(channels_.topology, buffer_.data(), encodeInto(msg, buffer_));
  }

  if (r.has_frame) {
    toposlam_lcm::place_t msg{};
    msg.utime = toMicroseconds(r.source_time_s);
    msg.frame = r.sequence;
    msg.place = e.place;
    msg.node = e.node;
    msg.probability = asFloat(e.probability);
    msg.is_new = e.is_new;
    msg.lambda2 = asFloat(r.lambda2);
    msg.num_alternatives = static_cast<std::int32_t>(e.alternatives.size());
    msg.alternatives.reserve(e.alternatives.size());
    for (const NodeProbability& alternative : e.alternatives) {
      toposlam_lcm::place_alternative_t a{};
      a.node = alternative.node;
      a.probability = asFloat(alternative.probability);
      msg.alternatives.push_back(a);
    }
    msg.map_revision = e.map_revision;
    msg.match_frame = r.revisit.match_frame;
    msg.match_score = asFloat(r.revisit.score);
    msg.match_place = r.revisit.match_place;
    msg.match_node = r.revisit.match_node;
    // Stamped last, just before publishing: the latency the message carries includes its own encoding.
    msg.publish_utime = monotonicMicroseconds();
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    const double now_s = static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
    msg.latency_ms = asFloat((now_s - r.captured_at_s) * 1e3);
    send(channels_.place, buffer_.data(), encodeInto(msg, buffer_));
  }
}

namespace {

/// The STATUS line's source part: "camera streaming (0 reconnects, 0 lost by the driver)" for a camera,
/// "simulator running", "reading images", "reading a video file" for the others (sourceStateName).
std::string sourceStateText(const toposlam_lcm::status_t& m) {
  for (const SourceKind kind : {SourceKind::Simulator, SourceKind::ImageFiles, SourceKind::VideoFile})
    if (m.source_state == sourceStateName(kind, SourceLink::Streaming)) return sourceActivityText(kind, SourceLink::Streaming);
  return "camera " + m.source_state + " (" + std::to_string(m.source_reconnects) + " reconnects, " +
         std::to_string(m.source_dropped) + " lost by the driver)";
}

}  // namespace

void LcmPipelineSink::publishStatus(const PipelineStatus& s) {
  toposlam_lcm::status_t msg{};
  msg.utime = monotonicMicroseconds();
  msg.state = s.state;
  msg.uptime_s = asFloat(s.uptime_s);
  msg.fps = asFloat(s.fps);
  msg.frames_captured = s.frames_captured;
  msg.frames_published = s.frames_published;
  msg.frames_dropped = s.frames_dropped;
  msg.queue_kept_waits = s.queue_kept_waits;
  msg.source_skipped = s.source_skipped;
  msg.source_state = sourceStateName(s.source_kind, s.source_link);
  msg.source_reconnects = s.source_reconnects;
  msg.source_reconnect_attempts = s.source_reconnect_attempts;
  msg.source_dropped = s.source_dropped;
  msg.latency_median_ms = asFloat(s.latency.median_ms);
  msg.latency_p99_ms = asFloat(s.latency.p99_ms);
  msg.latency_max_ms = asFloat(s.latency.max_ms);
  msg.cpu_percent = asFloat(s.cpu_percent);
  msg.places = s.places;
  msg.map_revision = s.map_revision;
  msg.maps_saved = s.maps_saved;
  msg.motion_messages = motion_ ? motion_->messages.load() : 0;
  msg.motion_state = toString(motion_ ? static_cast<MotionUse>(motion_->use.load()) : MotionUse::None);
  msg.motion_standing_frames = motion_ ? motion_->standing_frames.load() : 0;
  msg.motion_refused = motion_ ? motion_->refused.load() : 0;
  msg.motion_malformed = motion_ ? motion_->malformed.load() : 0;
  msg.motion_fragments_abandoned = motion_ ? motion_->fragments_abandoned.load() : 0;
  const SkippedFrames& skipped = s.source_skipped_by_reason;
  msg.source_skipped_unreadable = skipped[SkipReason::Unreadable];
  msg.source_skipped_truncated = skipped[SkipReason::Truncated];
  msg.source_skipped_corrupt = skipped[SkipReason::Corrupt];
  msg.source_skipped_too_large = skipped[SkipReason::TooLarge];
  msg.source_skipped_wrong_format = skipped[SkipReason::WrongFormat];
  msg.source_skipped_device_error = skipped[SkipReason::DeviceError];
  msg.source_skipped_other = skipped[SkipReason::Other];
  msg.num_stages = static_cast<std::int32_t>(s.stages.size());
  msg.stages.reserve(s.stages.size());
  for (const StageStatus& st : s.stages) {
    toposlam_lcm::stage_status_t m{};
    m.name = st.name;
    m.latency_median_ms = asFloat(st.latency.median_ms);
    m.latency_p99_ms = asFloat(st.latency.p99_ms);
    m.latency_max_ms = asFloat(st.latency.max_ms);
    m.processed = st.processed;
    m.dropped = st.dropped;
    m.queue_depth = static_cast<std::int32_t>(st.queue_depth);
    m.queue_capacity = static_cast<std::int32_t>(st.queue_capacity);
    m.cpu_percent = asFloat(st.cpu_percent);
    msg.stages.push_back(std::move(m));
  }
  send(channels_.status, buffer_.data(), encodeInto(msg, buffer_));
}

// --------------------------------------------------------------------------------------------------------

namespace {

void jsonNumber(JsonWriter& w, const char* key, float v) {
  w.key(key);
  if (std::isfinite(v))
    w.value(static_cast<double>(v));
  else
    w.null();
}

// ---- array lengths checked before the generated decoder trusts them ------------------------------------
// The lcm-gen decoders resize every array to its length field before reading the elements, so a
// negative length (std::length_error) or 10^8 (800 MB) would be allocated from a 100-byte message. This
// walks the wire format (big-endian, 8-byte type hash first, strings as int32 length incl. NUL + bytes)
// and refuses a length below 0 or above what the remaining bytes can hold.

struct WireField {
  enum Kind { Fixed, String, Length, Array } kind;
  int bytes = 0;                               ///< Fixed: size; Array: element size if fixed (0 = struct)
  const std::vector<WireField>* element = nullptr;  ///< Array of structs
};

using WireSchema = std::vector<WireField>;
WireField fixed(int bytes) { return {WireField::Fixed, bytes, nullptr}; }
WireField text() { return {WireField::String, 0, nullptr}; }
WireField length() { return {WireField::Length, 0, nullptr}; }
WireField array(int element_bytes) { return {WireField::Array, element_bytes, nullptr}; }
WireField array(const WireSchema& element) { return {WireField::Array, 0, &element}; }

class WireWalker {
 public:
  WireWalker(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool skip(std::size_t n) {
    if (n > size_ - pos_) return false;
    pos_ += n;
    return true;
  }
  bool int32(std::int32_t& v) {
    if (size_ - pos_ < 4) return false;
    const std::uint32_t u = (std::uint32_t{data_[pos_]} << 24) | (std::uint32_t{data_[pos_ + 1]} << 16) |
                            (std::uint32_t{data_[pos_ + 2]} << 8) | std::uint32_t{data_[pos_ + 3]};
    v = static_cast<std::int32_t>(u);
    pos_ += 4;
    return true;
  }
  bool walk(const WireSchema& schema) {
    std::int32_t last_length = 0;
    for (const WireField& f : schema) {
      switch (f.kind) {
        case WireField::Fixed:
          if (!skip(static_cast<std::size_t>(f.bytes))) return false;
          break;
        case WireField::String: {
          std::int32_t n = 0;
          // The length counts the terminating NUL, so it is >= 1: the generated decoder assigns len - 1
          // bytes, and 0 made that a length_error (found by fuzz_lcm_messages).
          if (!int32(n) || n < 1 || !skip(static_cast<std::size_t>(n))) return false;
          break;
        }
        case WireField::Length:
          if (!int32(last_length) || last_length < 0) return false;
          break;
        case WireField::Array:
          if (f.element == nullptr) {
            if (!skip(static_cast<std::size_t>(last_length) * static_cast<std::size_t>(f.bytes))) return false;
          } else {
            // Every struct element takes at least one byte, so a length beyond the bytes left is a lie.
            if (static_cast<std::size_t>(last_length) > size_ - pos_) return false;
            for (std::int32_t i = 0; i < last_length; ++i)
              if (!walk(*f.element)) return false;
          }
          break;
      }
    }
    return true;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

const WireSchema kPlace = {fixed(8 * 3 + 4 * 4 + 1 + 4), length(), array(8), fixed(8 + 8 + 4 * 3)};
const WireSchema kPlaceV1 = {fixed(8 * 3 + 4 * 4 + 1 + 4), length(), array(8), fixed(8)};  // before match_*
const WireSchema kPlaceEvent = {fixed(8 + 4 + 4 + 1 + 4 + 8 * 3 + 4 * 3), length(), array(1), fixed(8)};
const WireSchema kStageStatus = {text(), fixed(4 * 3 + 8 * 2 + 4 * 2 + 4)};
const WireSchema kStatus = {fixed(8),
                            text(),
                            fixed(4 + 4 + 8 * 5),
                            text(),
                            fixed(8 + 4 + 8 + 4 * 4 + 4 + 8 * 3),
                            text(),
                            fixed(8 * 4 + 8 * 7),
                            length(),
                            array(kStageStatus)};
const WireSchema kStatusV3 = {fixed(8),
                              text(),
                              fixed(4 + 4 + 8 * 5),
                              text(),
                              fixed(8 + 4 + 8 + 4 * 4 + 4 + 8 * 3),
                              text(),
                              fixed(8 + 8 + 8 + 8 * 7),
                              length(),
                              array(kStageStatus)};  // before motion_fragments_abandoned
const WireSchema kStatusV2 = {
    fixed(8),         text(),   fixed(4 + 4 + 8 * 5), text(), fixed(8 + 4 + 8 + 4 * 4 + 4 + 8 * 3), text(),
    fixed(8 + 8 + 8), length(), array(kStageStatus)};  // before source_skipped_*
const WireSchema kStatusV1 = {fixed(8), text(), fixed(4 + 4 + 8 * 5), text(), fixed(8 + 4 + 8 + 4 * 4 + 4 + 8 * 3),
                              text(), fixed(8), length(), array(kStageStatus)};  // before motion_refused
const WireSchema kTopologyNode = {fixed(4), length(), array(4), length(), array(8)};
const WireSchema kTopology = {fixed(8 + 8 + 8 + 4 + 4), length(), array(kTopologyNode), length(), array(12)};
const WireSchema kMotion = {fixed(8 * 7 + 1)};

template <typename Message>
bool decodeMessage(const void* data, std::size_t size, Message& msg, const std::string& kind) {
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max()) || !lcmArrayLengthsFit(kind, data, size))
    return false;
  try {
    return msg.decode(data, 0, static_cast<int>(size)) >= 0;
  } catch (const std::exception&) {  // bad_alloc, length_error: survived and counted as malformed
    return false;
  }
}

}  // namespace

bool decodePlaceMessage(const void* data, std::size_t size, toposlam_lcm::place_t& out) {
  if (decodeMessage(data, size, out, "place")) return true;
  toposlam_lcm::place_v1_t old{};
  if (!decodeMessage(data, size, old, "place_v1")) return false;
  // An old recording's place message as today's, with no per-frame match.
  out = toposlam_lcm::place_t{};
  out.utime = old.utime;
  out.publish_utime = old.publish_utime;
  out.frame = old.frame;
  out.latency_ms = old.latency_ms;
  out.place = old.place;
  out.node = old.node;
  out.probability = old.probability;
  out.is_new = old.is_new;
  out.lambda2 = old.lambda2;
  out.num_alternatives = old.num_alternatives;
  out.alternatives = old.alternatives;
  out.map_revision = old.map_revision;
  out.match_frame = -1;
  out.match_score = 0.0F;
  out.match_place = -1;
  out.match_node = -1;
  return true;
}

namespace {

/// A status message's source_skipped_<reason> as SkippedFrames.
SkippedFrames skippedFramesOf(const toposlam_lcm::status_t& m) {
  SkippedFrames skipped;
  skipped[SkipReason::Unreadable] = m.source_skipped_unreadable;
  skipped[SkipReason::Truncated] = m.source_skipped_truncated;
  skipped[SkipReason::Corrupt] = m.source_skipped_corrupt;
  skipped[SkipReason::TooLarge] = m.source_skipped_too_large;
  skipped[SkipReason::WrongFormat] = m.source_skipped_wrong_format;
  skipped[SkipReason::DeviceError] = m.source_skipped_device_error;
  skipped[SkipReason::Other] = m.source_skipped_other;
  return skipped;
}

/// The fields every version of status_t has, from an older recording's message; the newer ones read 0, and
/// the frames the source skipped are all "other" (the reason was not recorded).
template <typename OldStatus>
toposlam_lcm::status_t statusFromOld(const OldStatus& old) {
  toposlam_lcm::status_t out{};
  out.utime = old.utime;
  out.state = old.state;
  out.uptime_s = old.uptime_s;
  out.fps = old.fps;
  out.frames_captured = old.frames_captured;
  out.frames_published = old.frames_published;
  out.frames_dropped = old.frames_dropped;
  out.queue_kept_waits = old.queue_kept_waits;
  out.source_skipped = old.source_skipped;
  out.source_skipped_other = old.source_skipped;
  out.source_state = old.source_state;
  out.source_reconnects = old.source_reconnects;
  out.source_reconnect_attempts = old.source_reconnect_attempts;
  out.source_dropped = old.source_dropped;
  out.latency_median_ms = old.latency_median_ms;
  out.latency_p99_ms = old.latency_p99_ms;
  out.latency_max_ms = old.latency_max_ms;
  out.cpu_percent = old.cpu_percent;
  out.places = old.places;
  out.map_revision = old.map_revision;
  out.maps_saved = old.maps_saved;
  out.motion_messages = old.motion_messages;
  out.motion_state = old.motion_state;
  out.motion_standing_frames = old.motion_standing_frames;
  out.num_stages = old.num_stages;
  out.stages = old.stages;
  return out;
}

/// A TOPOSLAM_STATUS message as status_t or, failing that, as status_v3_t (recorded before
/// motion_fragments_abandoned existed: it reads 0), status_v2_t (before source_skipped_<reason> too) or
/// status_v1_t (before motion_refused and motion_malformed too; they then read 0).
bool decodeStatusMessage(const void* data, std::size_t size, toposlam_lcm::status_t& out) {
  if (decodeMessage(data, size, out, "status")) return true;
  if (toposlam_lcm::status_v3_t v3{}; decodeMessage(data, size, v3, "status_v3")) {
    out = statusFromOld(v3);
    out.motion_refused = v3.motion_refused;
    out.motion_malformed = v3.motion_malformed;
    out.source_skipped_unreadable = v3.source_skipped_unreadable;
    out.source_skipped_truncated = v3.source_skipped_truncated;
    out.source_skipped_corrupt = v3.source_skipped_corrupt;
    out.source_skipped_too_large = v3.source_skipped_too_large;
    out.source_skipped_wrong_format = v3.source_skipped_wrong_format;
    out.source_skipped_device_error = v3.source_skipped_device_error;
    out.source_skipped_other = v3.source_skipped_other;
    return true;
  }
  if (toposlam_lcm::status_v2_t v2{}; decodeMessage(data, size, v2, "status_v2")) {
    out = statusFromOld(v2);
    out.motion_refused = v2.motion_refused;
    out.motion_malformed = v2.motion_malformed;
    return true;
  }
  toposlam_lcm::status_v1_t v1{};
  if (!decodeMessage(data, size, v1, "status_v1")) return false;
  out = statusFromOld(v1);
  return true;
}

}  // namespace

bool lcmArrayLengthsFit(const std::string& kind, const void* data, std::size_t size) {
  const WireSchema* schema = kind == "place"         ? &kPlace
                             : kind == "place_v1"    ? &kPlaceV1
                             : kind == "place_event" ? &kPlaceEvent
                             : kind == "status"      ? &kStatus
                             : kind == "status_v1"   ? &kStatusV1
                             : kind == "status_v2"   ? &kStatusV2
                             : kind == "status_v3"   ? &kStatusV3
                             : kind == "topology"    ? &kTopology
                             : kind == "motion"      ? &kMotion
                                                     : nullptr;
  if (schema == nullptr || data == nullptr) return false;
  WireWalker walker(static_cast<const std::uint8_t*>(data), size);
  return walker.skip(8) && walker.walk(*schema);  // the type hash, then the fields
}

struct LcmSubscriber::Route {
  LcmSubscriber* self;
  std::string kind;
};

LcmSubscriber::LcmSubscriber(const std::string& url, const LcmChannels& known, const std::vector<std::string>& channels,
                             Callback callback)
    : lcm_(openLcm(url)), callback_(std::move(callback)) {
  for (const std::string& channel : channels) {
    const std::string kind = channelKind(known, channel);
    if (kind.empty())
      throw std::invalid_argument("unknown channel '" + channel + "': expected one of " + known.place + ", " +
                                  known.place_event + ", " + known.topology + ", " + known.status + ", " + known.motion);
    routes_.push_back(std::make_unique<Route>(Route{this, kind}));
    lcm_->subscribeFunction(channel, &LcmSubscriber::dispatch, routes_.back().get());
  }
  openFragmentMonitor(url, channels);
}

LcmSubscriber::~LcmSubscriber() = default;

void LcmSubscriber::openFragmentMonitor(const std::string& url, const std::vector<std::string>& channels) {
  const std::optional<UdpmAddress> address = parseUdpmUrl(effectiveLcmUrl(url));
  if (!address) return;  // memq://, file://, ...: no datagrams, nothing fragmented; the count stays 0
  LcmFragmentTrackerConfig config;
  config.channels = channels;
  try {
    monitor_ = std::make_unique<LcmFragmentMonitor>(*address, std::move(config));
  } catch (const std::exception& e) {
    fragments_abandoned_.store(-1);
    spdlog::warn("lcm: fragmented messages abandoned on {} are not counted (reported as -1): {}", url, e.what());
  }
}

LcmFragmentStats LcmSubscriber::fragmentStats() const { return monitor_ ? monitor_->stats() : LcmFragmentStats{}; }

bool LcmSubscriber::handle(int timeout_ms) {
  if (monitor_) return handleWithMonitor(timeout_ms);
  // lcm_handle_timeout waits in select(), which a signal interrupts with EINTR whatever SA_RESTART says
  // (signal(7)); that is the caller's cue to look at its stop flag, not an LCM failure.
  errno = 0;
  if (lcm_->handleTimeout(timeout_ms) >= 0) return true;
  return errno == EINTR;
}

// Waits on liblcm's descriptor and the fragment listener's together, so the listener is read as promptly as
// liblcm's own receive thread reads its socket (a full socket buffer would lose datagrams to us alone).
bool LcmSubscriber::handleWithMonitor(int timeout_ms) {
  pollfd waiting[2] = {{lcm_->getFileno(), POLLIN, 0}, {monitor_->fd(), POLLIN, 0}};
  const int ready = poll(waiting, 2, timeout_ms);
  if (ready < 0) return errno == EINTR;  // a signal: the caller's cue to look at its flags
  monitor_->drain(static_cast<double>(monotonicMicroseconds()) * 1e-6);
  fragments_abandoned_.store(monitor_->stats().abandoned);
  if ((waiting[0].revents & POLLIN) == 0) return (waiting[0].revents & (POLLERR | POLLNVAL)) == 0;
  errno = 0;
  return lcm_->handle() >= 0 || errno == EINTR;
}

void LcmSubscriber::dispatch(const lcm::ReceiveBuffer* buffer, const std::string& channel, Route* route) {
  LcmSubscriber& self = *route->self;
  ReceivedMessage out;
  if (!decodeLcmMessage(route->kind, channel, buffer->data, buffer->data_size, out)) {
    self.malformed_.fetch_add(1);
    return;
  }
  self.received_.fetch_add(1);
  if (self.callback_) self.callback_(out);
}

std::string channelKind(const LcmChannels& known, const std::string& channel) {
  if (channel == known.place) return "place";
  if (channel == known.place_event) return "place_event";
  if (channel == known.topology) return "topology";
  if (channel == known.status) return "status";
  if (channel == known.motion) return "motion";
  return "";
}

bool decodeLcmMessage(const std::string& kind, const std::string& channel, const void* data, std::size_t size,
                      ReceivedMessage& out) {
  out = ReceivedMessage{};
  out.channel = channel;
  out.kind = kind;
  std::ostringstream json;
  JsonWriter w(json, false);
  w.beginObject().field("channel", channel).field("kind", kind);
  bool ok = true;
  if (kind == "place") {
    // Recordings from before the per-frame answer carry place_v1_t: read with no match.
    toposlam_lcm::place_t m{};
    ok = decodePlaceMessage(data, size, m);
    if (ok) {
      out.frame = m.frame;
      out.node = m.node;
      out.place = m.place;
      out.is_new = m.is_new;
      out.match_frame = m.match_frame;
      out.match_node = m.match_node;
      w.field("utime", m.utime).field("publish_utime", m.publish_utime).field("frame", m.frame)
          .field("place", m.place).field("node", m.node);
      jsonNumber(w, "probability", m.probability);
      w.field("is_new", m.is_new != 0);
      jsonNumber(w, "lambda2", m.lambda2);
      jsonNumber(w, "latency_ms", m.latency_ms);
      w.key("alternatives").beginArray();
      for (const auto& a : m.alternatives) {
        w.beginObject().field("node", a.node);
        jsonNumber(w, "probability", a.probability);
        w.endObject();
      }
      w.endArray().field("map_revision", m.map_revision).field("match_frame", m.match_frame);
      jsonNumber(w, "match_score", m.match_score);
      w.field("match_place", m.match_place).field("match_node", m.match_node);
      char line[320];
      char back[96] = "";
      if (m.match_frame >= 0)
        std::snprintf(back, sizeof back, "  back at frame %lld (place %d, node %d, score %.2f)",
                      static_cast<long long>(m.match_frame), m.match_place, m.match_node,
                      static_cast<double>(m.match_score));
      std::snprintf(line, sizeof line, "place  frame %6lld  place %3d  node %3d  p=%.2f%s  rev %lld  latency %.1f ms%s",
                    static_cast<long long>(m.frame), m.place, m.node, static_cast<double>(m.probability),
                    m.is_new ? " new" : "", static_cast<long long>(m.map_revision), static_cast<double>(m.latency_ms),
                    back);
      out.summary = line;
    }
  } else if (kind == "place_event") {
    toposlam_lcm::place_event_t m{};
    ok = decodeMessage(data, size, m, kind);
    if (ok) {
      out.node = m.node;
      out.place = m.place;
      out.is_new = m.is_new;
      w.field("place", m.place).field("node", m.node).field("is_new", m.is_new != 0);
      jsonNumber(w, "probability", m.probability);
      w.field("first_frame", m.first_frame).field("last_frame", m.last_frame)
          .field("representative_frame", m.representative_frame).field("keypoints", m.keypoints)
          .field("thumbnail_width", m.thumbnail_width).field("thumbnail_height", m.thumbnail_height)
          .field("jpeg_bytes", m.jpeg_size).field("map_revision", m.map_revision);
      char line[256];
      std::snprintf(line, sizeof line, "EVENT  place %3d -> node %3d  %s  p=%.2f  frames %lld..%lld  representative %lld  jpeg %d bytes",
                    m.place, m.node, m.is_new ? "new node" : "revisit ", static_cast<double>(m.probability),
                    static_cast<long long>(m.first_frame), static_cast<long long>(m.last_frame),
                    static_cast<long long>(m.representative_frame), m.jpeg_size);
      out.summary = line;
    }
  } else if (kind == "topology") {
    toposlam_lcm::topology_t m{};
    ok = decodeMessage(data, size, m, kind);
    if (ok) {
      out.node = m.current_node;
      w.field("map_revision", m.map_revision).field("probability", m.probability).field("particles", m.particles)
          .field("current_node", m.current_node);
      w.key("nodes").beginArray();
      for (const auto& n : m.nodes) {
        w.beginObject().field("id", n.id).key("places").beginArray();
        for (int p : n.places) w.value(p);
        w.endArray().endObject();
      }
      w.endArray().key("edges").beginArray();
      for (const auto& e : m.edges) w.beginObject().field("from", e.from_node).field("to", e.to_node).field("count", e.count).endObject();
      w.endArray();
      char line[160];
      std::snprintf(line, sizeof line, "TOPOLOGY  rev %lld  %d nodes  %d edges  p=%.2f  current node %d",
                    static_cast<long long>(m.map_revision), m.num_nodes, m.num_edges, m.probability, m.current_node);
      out.summary = line;
    }
  } else if (kind == "status") {
    toposlam_lcm::status_t m{};
    ok = decodeStatusMessage(data, size, m);  // older recordings: status_v3_t, status_v2_t, status_v1_t
    if (ok) {
      w.field("state", m.state);
      jsonNumber(w, "fps", m.fps);
      w.field("frames_captured", m.frames_captured)
          .field("frames_published", m.frames_published)
          .field("frames_dropped", m.frames_dropped)
          .field("queue_kept_waits", m.queue_kept_waits)
          .field("source_state", m.source_state)
          .field("source_reconnects", m.source_reconnects)
          .field("source_reconnect_attempts", m.source_reconnect_attempts)
          .field("source_dropped", m.source_dropped)
          .field("source_skipped", m.source_skipped)
          .field("source_skipped_unreadable", m.source_skipped_unreadable)
          .field("source_skipped_truncated", m.source_skipped_truncated)
          .field("source_skipped_corrupt", m.source_skipped_corrupt)
          .field("source_skipped_too_large", m.source_skipped_too_large)
          .field("source_skipped_wrong_format", m.source_skipped_wrong_format)
          .field("source_skipped_device_error", m.source_skipped_device_error)
          .field("source_skipped_other", m.source_skipped_other);
      jsonNumber(w, "latency_median_ms", m.latency_median_ms);
      jsonNumber(w, "latency_p99_ms", m.latency_p99_ms);
      jsonNumber(w, "latency_max_ms", m.latency_max_ms);
      jsonNumber(w, "cpu_percent", m.cpu_percent);
      w.field("places", m.places).field("map_revision", m.map_revision).field("maps_saved", m.maps_saved)
          .field("motion_messages", m.motion_messages).field("motion_state", m.motion_state)
          .field("motion_standing_frames", m.motion_standing_frames).field("motion_refused", m.motion_refused)
          .field("motion_malformed", m.motion_malformed)
          .field("motion_fragments_abandoned", m.motion_fragments_abandoned);
      w.key("stages").beginArray();
      for (const auto& st : m.stages) {
        w.beginObject().field("name", st.name);
        jsonNumber(w, "latency_median_ms", st.latency_median_ms);
        jsonNumber(w, "latency_max_ms", st.latency_max_ms);
        w.field("processed", st.processed).field("dropped", st.dropped).field("queue_depth", st.queue_depth);
        jsonNumber(w, "cpu_percent", st.cpu_percent);
        w.endObject();
      }
      w.endArray();
      char line[320];
      std::snprintf(line, sizeof line,
                    "STATUS %s  %.1f fps  latency median %.1f / p99 %.1f ms  %lld published  %lld dropped  "
                    "%lld kept waits  cpu %.0f%%  ",
                    m.state.c_str(), static_cast<double>(m.fps), static_cast<double>(m.latency_median_ms),
                    static_cast<double>(m.latency_p99_ms), static_cast<long long>(m.frames_published),
                    static_cast<long long>(m.frames_dropped), static_cast<long long>(m.queue_kept_waits),
                    static_cast<double>(m.cpu_percent));
      out.summary = line + sourceStateText(m);
      if (const std::string skipped = skippedFramesText(skippedFramesOf(m)); !skipped.empty())
        out.summary += "  " + skipped;
      if (const std::string motion = motionStatusText(m.motion_state, m.motion_standing_frames, m.motion_refused,
                                                          m.motion_malformed, m.motion_fragments_abandoned);
          !motion.empty())
        out.summary += "  " + motion;
    }
  } else {
    toposlam_lcm::motion_t m{};
    ok = decodeMessage(data, size, m, kind);
    if (ok) {
      w.field("utime", m.utime).field("sequence", m.sequence).field("forward_m", m.forward_m)
          .field("turn_rad", m.turn_rad).field("moving", m.moving != 0);
      char line[160];
      std::snprintf(line, sizeof line, "MOTION #%lld  forward %.3f m  turn %.3f rad", static_cast<long long>(m.sequence),
                    m.forward_m, m.turn_rad);
      out.summary = line;
      out.motion_time_s = static_cast<double>(m.utime) * 1e-6;
      out.motion_distance_m = std::hypot(m.forward_m, m.lateral_m);
      out.motion_speed_mps = std::abs(m.linear_velocity_mps);
      out.motion_turn_rate_rps = std::abs(m.angular_velocity_rps);
    }
  }
  if (!ok) return false;
  w.endObject();
  out.json = json.str();
  return true;
}

}  // namespace toposlam
