/*
 * timing.h -- small helpers shared by the bench programs: a monotonic clock,
 * medians, peak memory, a UTC time stamp.
 */
#ifndef BENCH_TIMING_H
#define BENCH_TIMING_H

#include <stddef.h>

/** Seconds on CLOCK_MONOTONIC (arbitrary origin). */
double bench_now(void);

/** Median of x (n >= 1 values); sorts x in place. 0 for n == 0. */
double bench_median(double *x, size_t n);

/** Peak resident set size of this process so far, kB (getrusage); -1 if unknown. */
long bench_peak_rss_kb(void);

/** Resident set size of this process now, bytes (/proc/self/statm); -1 if unknown. */
long bench_current_rss_bytes(void);

/** Current UTC time as "YYYY-MM-DDTHH:MM:SSZ" into buf (size >= 21). */
void bench_utc_stamp(char *buf, size_t size);

#endif /* BENCH_TIMING_H */
