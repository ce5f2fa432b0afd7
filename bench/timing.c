/*
 * timing.c -- see timing.h.
 */
#define _POSIX_C_SOURCE 200809L

#include "timing.h"

#include <stdlib.h>
#include <sys/resource.h>
#include <stdio.h>
#include <time.h>
#include <unistd.h>

double bench_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int compare_doubles(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double bench_median(double *x, size_t n)
{
    if (n == 0) {
        return 0.0;
    }
    qsort(x, n, sizeof *x, compare_doubles);
    return (n % 2 == 1) ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

long bench_peak_rss_kb(void)
{
    struct rusage usage;
    if (getrusage(RUSAGE_SELF, &usage) != 0) {
        return -1;
    }
    return (long)usage.ru_maxrss; /* kB on Linux */
}

void bench_utc_stamp(char *buf, size_t size)
{
    const time_t now = time(NULL);
    struct tm utc;
    if (size == 0) {
        return;
    }
    buf[0] = '\0';
    if (gmtime_r(&now, &utc) != NULL) {
        strftime(buf, size, "%Y-%m-%dT%H:%M:%SZ", &utc);
    }
}

long bench_current_rss_bytes(void)
{
    long pages_total = 0, pages_resident = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    int n;
    if (f == NULL) {
        return -1;
    }
    n = fscanf(f, "%ld %ld", &pages_total, &pages_resident);
    fclose(f);
    return n == 2 ? pages_resident * sysconf(_SC_PAGESIZE) : -1;
}
