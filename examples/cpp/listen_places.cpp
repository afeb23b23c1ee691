// listen_places.cpp: print toposlamd's place estimates (channel TOPOSLAM_PLACE, one per frame).
// Usage: listen_places [COUNT] [LCM_URL]  (COUNT 0: until 10 s without a message; URL: toposlam.yaml lcm.url)
// Build: g++ -std=c++17 -fno-strict-aliasing listen_places.cpp $(pkg-config --cflags --libs toposlam-lcm)
#include <cstdio>
#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <toposlam_lcm/place_t.hpp>

// A plain function and an untyped subscription: liblcm 1.3's handler-object subscriptions trip
// UndefinedBehaviorSanitizer's checks inside lcm-cpp-impl.hpp.
static void onPlace(const lcm::ReceiveBuffer* buffer, const std::string&, long* seen) {
  toposlam_lcm::place_t p;
  if (p.decode(buffer->data, 0, static_cast<int>(buffer->data_size)) < 0) return;
  // node: of the last place whose filter step finished; now: the node this frame is back in (the earlier frame
  // it matches, p.match_frame, lies in it), -1 while it is no known node.
  std::printf("frame %lld place %d node %d p=%.2f now %d\n", static_cast<long long>(p.frame), p.place, p.node,
              static_cast<double>(p.probability), p.match_node);
  std::fflush(stdout);
  ++*seen;
}

int main(int argc, char** argv) {
  const long count = argc > 1 ? std::atol(argv[1]) : 0;
  lcm::LCM lcm(argc > 2 ? argv[2] : "udpm://239.255.76.67:7667?ttl=0");
  if (!lcm.good()) return 1;
  long seen = 0;
  lcm.subscribeFunction("TOPOSLAM_PLACE", &onPlace, &seen);
  while ((count == 0 || seen < count) && lcm.handleTimeout(10000) > 0) continue;
  return seen > 0 ? 0 : 1;
}
