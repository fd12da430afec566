/* The CLI's outputs survive being killed: `ibl bake` over an existing bake is interrupted by
 * SIGKILL and SIGINT at random moments, many times, and after every trial the folder is one
 * complete bake, the old or the new (every file the manifest lists loads, and the chain is
 * the one the manifest describes); concurrent writers of one folder never mix; leftovers of
 * killed runs are cleaned by the next run. */
#include "test_support.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* A deterministic sequence of delays, so that a failure can be replayed. */
static unsigned long long rng_state = 0x9E3779B97F4A7C15ull;
static double uniform(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* Two bakes that differ in every file: the old (ggx, 16) and the new (phong, 32). */
static const char *const bake_options[2][12] = {
    {"--size", "16", "--working-size", "32", "--lut-size", "16", "--irradiance-size", "4",
     "--preview-width", "64", NULL},
    {"--size", "32", "--filter", "phong", "--working-size", "32", "--lut-size", "16",
     "--irradiance-size", "4", "--preview-width", "64"},
};

static pid_t start(int which, const char *dir)
{
    const char *argv[20] = {IBL_CLI_PATH, "bake", "-o", dir, "-q"};
    int n = 5;
    for (int i = 0; i < 12 && bake_options[which][i] != NULL; i++) argv[n++] = bake_options[which][i];
    argv[n] = NULL;
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        if (null >= 0) dup2(null, 2);
        execv(IBL_CLI_PATH, (char *const *)argv);
        _exit(127);
    }
    return pid;
}

static int finish(pid_t pid)
{
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/* The folder holds one complete bake: which one (0 old, 1 new). */
static int complete_bake(ibl_context *ctx, const char *dir)
{
    ibl_bake_data b;
    ibl_status st = ibl_bake_load(ctx, dir, NULL, &b);
    if (st != IBL_OK) fail_msg("%s", ibl_context_message(ctx));
    int which = b.specular_info.filter == IBL_FILTER_PHONG;
    assert_int_equal(b.specular.size, which ? 32 : 16);
    assert_non_null(b.irradiance.data);
    assert_non_null(b.splitsum.pixels);
    ibl_bake_free(ctx, &b);
    return which;
}

static int leftovers(const char *root)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "ls -a '%s' | grep -q '^\\.bake\\.'", root);
    return system(cmd) == 0;
}

static void killed_bakes(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const char *root = test_path("kill");
    assert_int_equal(mkdir(root, 0777), 0);
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/bake", root);
    /* how long a whole bake takes here: the delays span it */
    double t0 = now();
    assert_int_equal(finish(start(1, dir)), 0);
    double span = now() - t0;
    assert_int_equal(finish(start(0, dir)), 0);
    int seen[2] = {0, 0}, completed = 0;
    enum { TRIALS = 40 };
    for (int trial = 0; trial < TRIALS; trial++) {
        int which = trial % 2, sig = trial % 3 == 2 ? SIGINT : SIGKILL;
        double delay = uniform() * span * 1.1;
        pid_t pid = start(which, dir);
        struct timespec ts = {(time_t)delay, (long)((delay - (double)(time_t)delay) * 1e9)};
        nanosleep(&ts, NULL);
        kill(pid, sig);
        int rc = finish(pid);
        /* SIGINT: a clean cancel (130) or done before it came (0); SIGKILL: killed or done */
        if (sig == SIGINT) assert_true(rc == 130 || rc == 0);
        else assert_true(rc == 128 + SIGKILL || rc == 0);
        completed += rc == 0;
        seen[complete_bake(ctx, dir)]++;
    }
    print_message("%d trials over %.2f s bakes: %d finished, old bake kept %d times, new %d\n",
                  TRIALS, span, completed, seen[0], seen[1]);
    /* the next run cleans what killed runs left */
    assert_int_equal(finish(start(0, dir)), 0);
    assert_int_equal(complete_bake(ctx, dir), 0);
    assert_false(leftovers(root));
    ibl_context_destroy(ctx);
}

/* Four writers at once: each finishes or is refused by the lock, and the folder holds one
 * complete bake at the end. */
static void concurrent_bakes(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const char *root = test_path("race");
    assert_int_equal(mkdir(root, 0777), 0);
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/bake", root);
    for (int round = 0; round < 3; round++) {
        pid_t pid[4];
        for (int i = 0; i < 4; i++) pid[i] = start(i % 2, dir);
        int ok = 0;
        for (int i = 0; i < 4; i++) {
            int rc = finish(pid[i]);
            assert_true(rc == 0 || rc == 1); /* 1: "being written by another process" */
            ok += rc == 0;
        }
        assert_true(ok >= 1);
        complete_bake(ctx, dir);
        assert_false(leftovers(root));
    }
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(killed_bakes),
        cmocka_unit_test(concurrent_bakes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
