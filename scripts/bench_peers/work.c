/* The benchmark's trial: reads one JSON config ({"x": 3, "seed": 7}), spins until it has used
 * WORK_MS (default 10) milliseconds of its own CPU time, and prints one result line
 * {"value": N}, N a function of x and seed alone. With --worker it answers each stdin line in
 * turn (qsweep's worker protocol). C, not Python: Python's own start (about 20 ms) would be
 * twice the work and would differ by tool; this program starts in well under 1 ms. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double cpu_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

/* The integer after "name": in line (0 when absent). */
static long field(const char *line, const char *name) {
    char key[64];
    snprintf(key, sizeof key, "\"%s\"", name);
    const char *p = strstr(line, key);
    if (!p) return 0;
    p = strchr(p + strlen(key), ':');
    return p ? strtol(p + 1, NULL, 10) : 0;
}

static void trial(const char *line, double work_ms) {
    unsigned long long v = (unsigned long long)field(line, "x") * 1000003ULL + field(line, "seed");
    double until = cpu_ms() + work_ms;
    volatile unsigned long long sink = v;
    while (cpu_ms() < until)
        for (int i = 0; i < 1000; i++) sink = sink * 6364136223846793005ULL + 1442695040888963407ULL;
    for (int i = 0; i < 16; i++) v = v * 6364136223846793005ULL + 1442695040888963407ULL;
    printf("{\"value\": %llu}\n", v >> 33);
    fflush(stdout);
}

int main(int argc, char **argv) {
    const char *env = getenv("WORK_MS");
    double work_ms = env ? atof(env) : 10.0;
    static char line[1 << 16];
    if (argc > 1 && strcmp(argv[1], "--worker") == 0) {
        while (fgets(line, sizeof line, stdin))
            if (line[0] != '\n') trial(line, work_ms);
        return 0;
    }
    size_t n = fread(line, 1, sizeof line - 1, stdin);
    line[n] = 0;
    trial(line, work_ms);
    return 0;
}
