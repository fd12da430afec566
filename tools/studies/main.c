/* ibl_studies: runs the studies of docs/STUDIES.md and writes their tables as Markdown
 * fragments (tools/studies/run.sh splices them into the document).
 *
 * usage: ibl_studies --hdri DIR --out DIR [--images DIR] [--machine TEXT] [--date TEXT] [--quick]
 *                    [--study kernels|blinn|artefact|ambient|speed]...
 */
#include "studies.h"

#include <string.h>

static const struct {
    const char *name;
    int (*run)(const study_env *env);
} studies[] = {
    {"kernels", study_kernels}, {"blinn", study_blinn_factor}, {"artefact", study_artefact},
    {"ambient", study_ambient}, {"speed", study_speed},
};
enum { STUDY_COUNT = sizeof studies / sizeof studies[0] };

static int usage(void)
{
    fprintf(stderr, "usage: ibl_studies --hdri DIR --out DIR [--images DIR] [--machine TEXT] [--date TEXT]\n"
                    "                   [--quick]\n"
                    "                   [--study kernels|blinn|artefact|ambient|speed]...\n");
    return 2;
}

int main(int argc, char **argv)
{
    study_env env = {.machine = "this machine", .date = "today"};
    int chosen[STUDY_COUNT] = {0}, any = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--quick") == 0) {
            env.quick = 1;
            continue;
        }
        if (!v) return usage();
        i++;
        if (strcmp(a, "--hdri") == 0) env.hdri_dir = v;
        else if (strcmp(a, "--out") == 0) env.out_dir = v;
        else if (strcmp(a, "--images") == 0) env.image_dir = v;
        else if (strcmp(a, "--machine") == 0) env.machine = v;
        else if (strcmp(a, "--date") == 0) env.date = v;
        else if (strcmp(a, "--study") == 0) {
            int found = 0;
            for (int s = 0; s < STUDY_COUNT; s++)
                if (strcmp(v, studies[s].name) == 0) chosen[s] = found = any = 1;
            if (!found) return usage();
        } else {
            return usage();
        }
    }
    if (!env.hdri_dir || !env.out_dir) return usage();
    /* one thread: the timings are single-core figures and every result is bit-identical at
     * any thread count anyway */
    ibl_context_desc cd = {.threads = 1};
    if (ibl_context_create(&cd, &env.ctx) != IBL_OK) {
        fprintf(stderr, "studies: cannot create a context\n");
        return 1;
    }
    int rc = 0;
    for (int s = 0; s < STUDY_COUNT && !rc; s++) {
        if (any && !chosen[s]) continue;
        double t0 = study_now_ms();
        rc = studies[s].run(&env);
        fprintf(stderr, "studies: %s %s in %.1f s\n", studies[s].name, rc ? "failed" : "done",
                (study_now_ms() - t0) / 1e3);
    }
    ibl_context_destroy(env.ctx);
    return rc;
}
