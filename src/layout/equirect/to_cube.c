/* Equirect -> cube: the conversion's driver. Each cube texel is the solid-angle-weighted mean of
 * k x k sample cells on its face-plane footprint, each weighing dA / |d|^3 (the solid angle of
 * a face-plane element at d, the face one unit from the centre; the same weight as the exact
 * texel solid angles of src/core/cubemap.c, after Driscoll 2012). k follows the texel's extent
 * in source rows and columns (SAMPLES_PER_ROW / _COLUMN per pixel crossed, batch_lanes.h), and
 * every pixel is reached anyway because each sample is not a point but an energy-preserving
 * window over its cell (area_windows.c). Texels near a pole and crossed by many columns of a
 * polar face are handled by polar_texels.c. Measured accuracy: tests/test_layout.c and
 * docs/CONVENTIONS.md.
 *
 * Speed (docs/PERFORMANCE.md, "Equirect to cube"): the samples of a texel row are gathered in
 * batches of EQ_BATCH. The float lanes (batch_lanes.h, four lanes wide, or eight with AVX2
 * where src/core/cpu.h allows it: the same bits) compute every window and the 4 x 4 taps of
 * those at most two pixels wide and tall, which is nearly all of them; the rest (under 1/16
 * pixel, wider than two) are computed in double (batch_double.c). Each texel row is one task,
 * and every texel is summed in its samples' order, so the result does not depend on the
 * thread count. */
#include "equirect_internal.h"

#include <math.h>

/* The polar region handled by direct integration: at least 3 texels and this many rows. */
static const double POLE_ROWS = 4.0;
/* Texels of the faces around the poles that take this many samples per axis or more take one
 * window per source column instead (ibl__eq_polar_columns). The two methods blur a texel's
 * edge differently, so their border is not exactly energy-neutral: at this k the grid's
 * windows reach only 1/16 of the texel past it in latitude (and it lies inside the directly
 * integrated polar region for cubes about as fine as the picture). */
enum { POLAR_COLUMNS_K = 8 };

/* Writes the mean of the texel being summed, if any. */
static void batch_emit(eq_batch *bt, float *out)
{
    if (bt->cur >= 0) {
        v4f mean = __builtin_convertvector(bt->acc * (1.0 / bt->wsum), v4f);
        memcpy(out + (size_t)bt->cur * 4, &mean, sizeof mean);
    }
    bt->cur = -1;
}

void ibl__eq_batch_flush(const eq_job *job, int face, eq_batch *bt, float *out)
{
    int n = bt->n, n8 = (n + 7) & ~7;
    for (int i = n; i < n8; i++) {
        /* lanes past the batch: the face's centre (unused) */
        bt->fsc[i] = bt->ftc[i] = 0.0f;
        bt->fsub[i] = 1.0f;
    }
    int all_fast = job->kernels->windows(&job->lanes[face], bt, n8, n) == n;
    eq_double_windows *dw = bt->slow;
    dw->n = 0;
    for (int i = 0; i < n && !all_fast; i++) {
        if (bt->fast[i]) continue;
        int j = dw->n++;
        dw->sc[j] = bt->fsc[i];
        dw->tc[j] = bt->ftc[i];
        dw->sub[j] = bt->fsub[i];
        dw->preset[j] = bt->fsub[i] == 0.0f;
        if (dw->preset[j]) memcpy(dw->given[j], bt->given[i], sizeof dw->given[j]);
    }
    if (dw->n) ibl__eq_double_windows(job, face, dw);
    job->kernels->accumulate(job, bt, out);
    bt->n = 0;
}

/* Appends one sample at the centre of each of texels [tx0, tx0 + count) (the runs where every
 * texel takes one, most runs of the faces around the equator). */
static void add_centre_samples(const eq_job *job, int face, int ty, int tx0, int count,
                               eq_batch *bt, float *out)
{
    const double cell = 2.0 / job->out->size;
    const float fcell = (float)cell, ftc_mid = (float)(-1.0 + (ty + 0.5) * cell);
    for (int r = 0; r < count;) {
        if (bt->n == EQ_BATCH) ibl__eq_batch_flush(job, face, bt, out);
        int n0 = bt->n, m = count - r < EQ_BATCH - n0 ? count - r : EQ_BATCH - n0;
        for (int q = 0; q < m; q++) {
            bt->texel[n0 + q] = tx0 + r + q;
            bt->fsc[n0 + q] = (float)(-1.0 + (tx0 + r + q + 0.5) * cell);
            bt->ftc[n0 + q] = ftc_mid;
            bt->fsub[n0 + q] = fcell;
        }
        bt->n += m;
        r += m;
    }
}

/* Appends texel (tx, ty)'s k x k samples, a row of them at a time (k <= 64 < EQ_BATCH). */
static void add_grid_samples(const eq_job *job, int face, int tx, int ty, int k, eq_batch *bt,
                             float *out)
{
    const double cell = 2.0 / job->out->size;
    const double sub = cell / k;
    const float fsub = (float)sub;
    float sci[64];
    for (int i = 0; i < k; i++) sci[i] = (float)(-1.0 + tx * cell + (i + 0.5) * sub);
    for (int j = 0; j < k; j++) {
        if (bt->n + k > EQ_BATCH) ibl__eq_batch_flush(job, face, bt, out);
        float tcj = (float)(-1.0 + ty * cell + (j + 0.5) * sub);
        int *texel = bt->texel + bt->n;
        float *fsc = bt->fsc + bt->n, *ftc = bt->ftc + bt->n, *fs = bt->fsub + bt->n;
        for (int i = 0; i < k; i++) {
            texel[i] = tx;
            fsc[i] = sci[i];
            ftc[i] = tcj;
            fs[i] = fsub;
        }
        bt->n += k;
    }
}

/* One texel row of one face (task index = face * N + row). */
static void row_task(void *arg, int index)
{
    const eq_job *job = arg;
    int N = job->out->size, face = index / N, ty = index % N;
    float *out = ibl_cubemap_face(job->out, 0, face) + (size_t)ty * N * 4;
    const double cell = 2.0 / N; /* texel edge on the face plane */
    eq_batch bt;
    eq_double_windows dw;
    bt.n = 0;
    bt.cur = -1;
    bt.slow = &dw;
    /* (the given windows' lanes are read for every sample, and selected only where given) */
    memset(bt.gwt, 0, sizeof bt.gwt);
    memset(bt.gpx, 0, sizeof bt.gpx);
    memset(bt.gpy, 0, sizeof bt.gpy);
    memset(bt.gwpx, 0, sizeof bt.gwpx);
    memset(bt.ghpx, 0, sizeof bt.ghpx);
    memset(bt.gst, 0, sizeof bt.gst);
    memset(bt.gct, 0, sizeof bt.gct);
    int ks[EQ_TEXEL_RUN];
    const float fcell = (float)cell, ftc_mid = (float)(-1.0 + (ty + 0.5) * cell);
    for (int tx0 = 0; tx0 < N; tx0 += EQ_TEXEL_RUN) {
        int run = N - tx0 < EQ_TEXEL_RUN ? N - tx0 : EQ_TEXEL_RUN;
        if (job->fixed_k == 0)
            job->kernels->sample_counts(&job->lanes[face], ty, tx0, (run + 7) & ~7, ks);
        int all_one = job->fixed_k == 1;
        if (job->fixed_k == 0) {
            all_one = 1;
            for (int r = 0; r < run; r++) all_one &= ks[r] == 1;
        }
        if (all_one) {
            add_centre_samples(job, face, ty, tx0, run, &bt, out);
            continue;
        }
        for (int r = 0; r < run; r++) {
            int tx = tx0 + r, k = job->fixed_k ? job->fixed_k : ks[r];
            if (k == 0) {
                ibl__eq_polar_texel(job, face, tx, ty, out + (size_t)tx * 4);
                continue;
            }
            if (k >= POLAR_COLUMNS_K && job->fixed_k == 0 &&
                ibl__eq_polar_columns(job, face, tx, ty, &bt, out))
                continue;
            if (k == 1) {
                if (bt.n == EQ_BATCH) ibl__eq_batch_flush(job, face, &bt, out);
                bt.texel[bt.n] = tx;
                bt.fsc[bt.n] = (float)(-1.0 + (tx + 0.5) * cell);
                bt.ftc[bt.n] = ftc_mid;
                bt.fsub[bt.n] = fcell;
                bt.n++;
                continue;
            }
            add_grid_samples(job, face, tx, ty, k, &bt, out);
        }
    }
    if (bt.n) ibl__eq_batch_flush(job, face, &bt, out);
    batch_emit(&bt, out);
}

/* The mean of each source row (the value of windows a whole turn wide), MEAN_ROWS rows per
 * task: each row is summed alone, in order, whichever thread takes it. */
enum { MEAN_ROWS = 16 };
typedef struct row_mean_job {
    const ibl_image *image;
    float *mean;
} row_mean_job;

static void row_mean_task(void *arg, int index)
{
    const row_mean_job *j = arg;
    int W = j->image->width, H = j->image->height;
    for (int r = index * MEAN_ROWS; r < H && r < (index + 1) * MEAN_ROWS; r++) {
        double s[4] = {0, 0, 0, 0};
        const float *p = j->image->pixels + (size_t)r * W * 4;
        for (int x = 0; x < W; x++)
            for (int c = 0; c < 4; c++) s[c] += p[(size_t)x * 4 + c];
        for (int c = 0; c < 4; c++) j->mean[(size_t)r * 4 + c] = (float)(s[c] / W);
    }
}

/* Each face's axes and the picture's sizes in float, for the lanes. */
static void lane_faces(eq_job *job)
{
    int W = job->im->width, H = job->im->height, N = job->out->size;
    /* The polar region: 3 texels, and at least POLE_ROWS source rows. */
    double cell = 2.0 / N;
    double radius = fmin(fmax(atan(3.0 * cell), POLE_ROWS * IBL_PI / H), IBL_HALF_PI);
    double pole_radius2 = sin(radius) * sin(radius);
    for (int f = 0; f < 6; f++) {
        eq_lane_face *lf = &job->lanes[f];
        for (int i = 0; i < 3; i++) {
            lf->m[i] = (float)job->basis[f][0][i];
            lf->a[i] = (float)job->basis[f][1][i];
            lf->b[i] = (float)job->basis[f][2][i];
        }
        lf->W = W;
        lf->H = H;
        lf->R = eq_polar_box_rows(H);
        lf->narrow_ok = W >= 8;
        lf->N = N;
        lf->pole_radius2 = (float)pole_radius2;
    }
}

ibl_status ibl__equirect_to_cube(ibl_context *ctx, const ibl_image *image, const ibl__frame *frame,
                                 int samples_per_axis, ibl_cubemap *out)
{
    int W = image->width, H = image->height;
    float *mean = ibl_alloc(ctx, (size_t)H * 4 * sizeof(float));
    if (!mean) return ibl_context_status(ctx);
    row_mean_job rm = {image, mean};
    ibl_parallel_for(ctx, (H + MEAN_ROWS - 1) / MEAN_ROWS, row_mean_task, &rm);
    double *cs = ibl_alloc(ctx, (size_t)W * 2 * sizeof(double));
    if (!cs) {
        ibl_free(ctx, mean);
        return ibl_context_status(ctx);
    }
    for (int j = 0; j < W; j++) {
        double phi = IBL_TWO_PI * ((j + 0.5) / W - 0.5);
        cs[j] = sin(phi);
        cs[W + j] = cos(phi);
    }
    eq_job job;
    memset(&job, 0, sizeof job);
    job.col_sin = cs;
    job.col_cos = cs + W;
    job.im = image;
    job.row_mean = mean;
    job.out = out;
    job.fixed_k = samples_per_axis;
    ibl__picture_basis(frame, job.basis);
    lane_faces(&job);
    job.kernels = &ibl__eq_lanes_4;
#if EQ_HAVE_LANES_8
    if (ibl__cpu_has(ctx, IBL__CPU_AVX2_FMA)) job.kernels = &ibl__eq_lanes_8;
#endif
    ibl_parallel_for(ctx, 6 * out->size, row_task, &job);
    ibl_free(ctx, cs);
    ibl_free(ctx, mean);
    return IBL_OK;
}
