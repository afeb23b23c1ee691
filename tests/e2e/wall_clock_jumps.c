/* An LD_PRELOAD library for the wall-clock test (check_wall_clock_jumps.py, docs/reliability.md "Clock
 * jumps"): the process's wall clock (CLOCK_REALTIME and its relatives, gettimeofday, time) jumps as an NTP
 * step on a robot without RTC would, over and over: every TOPOSLAM_WALL_JUMP_PERIOD_S seconds (default 1)
 * it is honest, then an hour behind, then a day ahead, then honest again. CLOCK_MONOTONIC is left alone,
 * as the kernel leaves it. Only what reads the clock through libc is fooled (timed waits the kernel does
 * on CLOCK_REALTIME are not): that is how durations measured on the wall clock would go wrong. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdlib.h>
#include <string.h>
#include <sys/time.h>
#include <time.h>

typedef int (*clock_gettime_fn)(clockid_t, struct timespec*);

static clock_gettime_fn real_clock_gettime(void) {
  static clock_gettime_fn real = 0;
  if (!real) {
    void* symbol = dlsym(RTLD_NEXT, "clock_gettime");
    memcpy(&real, &symbol, sizeof real); /* POSIX: a data pointer that holds a function's address */
  }
  return real;
}

static long wall_offset_s(void) {
  static double period_s = 0.0;
  if (period_s <= 0.0) {
    const char* text = getenv("TOPOSLAM_WALL_JUMP_PERIOD_S");
    period_s = text ? atof(text) : 1.0;
    if (period_s <= 0.0) period_s = 1.0;
  }
  struct timespec now;
  if (real_clock_gettime()(CLOCK_MONOTONIC, &now) != 0) return 0;
  const double seconds = (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
  switch ((long)(seconds / period_s) % 3) {
    case 1: return -3600;  /* an hour behind */
    case 2: return 86400;  /* a day ahead */
    default: return 0;
  }
}

int clock_gettime(clockid_t clock, struct timespec* ts) {
  const int result = real_clock_gettime()(clock, ts);
  if (result == 0 && (clock == CLOCK_REALTIME || clock == CLOCK_REALTIME_COARSE || clock == CLOCK_TAI))
    ts->tv_sec += wall_offset_s();
  return result;
}

int gettimeofday(struct timeval* tv, void* tz) {
  (void)tz;
  struct timespec ts;
  if (clock_gettime(CLOCK_REALTIME, &ts) != 0) return -1;
  tv->tv_sec = ts.tv_sec;  /* glibc declares tv non-null */
  tv->tv_usec = ts.tv_nsec / 1000;
  return 0;
}

time_t time(time_t* out) {
  struct timespec ts;
  if (clock_gettime(CLOCK_REALTIME, &ts) != 0) return (time_t)-1;
  if (out) *out = ts.tv_sec;
  return ts.tv_sec;
}
