// listen_places.cpp: print toposlamd's place estimates (channel TOPOSLAM_PLACE, one per frame).
// Usage: listen_places [COUNT] [LCM_URL]  (COUNT 0: until 10 s without a message; URL: toposlam.yaml lcm.url)
// Build: g++ -std=c++17 -fno-strict-aliasing listen_places.cpp $(pkg-config --cflags --libs toposlam-lcm)
#include <cstdio>
#include <cstdlib>
#include <string>

#include <lcm/lcm-cpp.hpp>
#include <toposlam_lcm/place_t.hpp>

struct Printer {
  long seen = 0;
  void onPlace(const lcm::ReceiveBuffer*, const std::string&, const toposlam_lcm::place_t* p) {
    std::printf("frame %lld place %d node %d p=%.2f\n", static_cast<long long>(p->frame), p->place, p->node,
                static_cast<double>(p->probability));
    std::fflush(stdout);
    ++seen;
  }
};

int main(int argc, char** argv) {
  const long count = argc > 1 ? std::atol(argv[1]) : 0;
  lcm::LCM lcm(argc > 2 ? argv[2] : "udpm://239.255.76.67:7667?ttl=0");
  if (!lcm.good()) return 1;
  Printer printer;
  lcm.subscribe("TOPOSLAM_PLACE", &Printer::onPlace, &printer);
  while ((count == 0 || printer.seen < count) && lcm.handleTimeout(10000) > 0) {
  }
  return printer.seen > 0 ? 0 : 1;
}
