/* Study 3: tri-Ace 2010's "HDR IBL Artifact" table. The talk evaluates its normalised
 * Blinn-Phong specular term for a light seen in the mirror direction (h = n, so (n.h)^s = 1 and
 * n.l / max(n.l, n.v) = 1): reflected radiance = L x Schlick(F0, E.H) x (0.0397436 s +
 * 0.0856832), with F0 = 0.04 (refractive index 1.5), and compares a grazing worst case with a
 * head-on best case. Here the same product from the library's own functions
 * (ibl_fresnel_schlick, ibl_blinn_phong_norm, ibl_blinn_normalization_factor) against the
 * closed form in float64, at the table's shininess and at the shininess that reproduces the
 * printed results; then what AO and the specular occlusion formulas leave of the worst case. */
#include "studies.h"

#include <math.h>

typedef struct talk_row {
    const char *name;
    double light, e_dot_h, schlick, shininess, result; /* as printed in the talk */
} talk_row;

static const talk_row rows[2] = {
    {"worst case", 10.0, 0.1, 0.61, 500.0, 12.644},
    {"best case", 1.0, 1.0, 0.04, 10.0, 0.00502},
};

static double schlick_d(double f0, double c)
{
    return f0 + (1.0 - f0) * pow(1.0 - c, 5.0);
}

static double triace_norm_d(double s)
{
    return 0.0397436 * s + 0.0856832;
}

/* The shininess at which L x Schlick x norm(s) equals the printed result, with the printed
 * (rounded) Schlick value: the closed form solved for s. */
static double shininess_for(const talk_row *r)
{
    return (r->result / (r->light * r->schlick) - 0.0856832) / 0.0397436;
}

static void value_table(FILE *md)
{
    fprintf(md, "| case | light | E·H | Schlick: talk / library | shininess | talk's result | library at the "
                "talk's shininess | exact normalisation | shininess that gives the talk's result | library "
                "there (talk's Schlick) |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < 2; i++) {
        const talk_row *r = &rows[i];
        float f = ibl_fresnel_schlick(0.04f, (float)r->e_dot_h);
        double lib = r->light * f * ibl_blinn_phong_norm((float)r->shininess);
        double exact = r->light * f * ibl_blinn_normalization_factor(IBL_BLINN_EXACT, r->shininess);
        double s_fit = shininess_for(r);
        double lib_fit = r->light * r->schlick * ibl_blinn_phong_norm((float)s_fit);
        double ref_fit = r->light * r->schlick * triace_norm_d(s_fit);
        fprintf(md, "| %s | %g | %g | %.2f / %.4f | %g | %g | %.4g | %.4g | %.3f | %.5g (float64: %.5g) |\n",
                r->name, r->light, r->e_dot_h, r->schlick, (double)f, r->shininess, r->result, lib, exact,
                s_fit, lib_fit, ref_fit);
    }
    double lib_ratio = (10.0 * ibl_fresnel_schlick(0.04f, 0.1f) * ibl_blinn_phong_norm(500.0f)) /
                       (1.0 * ibl_fresnel_schlick(0.04f, 1.0f) * ibl_blinn_phong_norm(10.0f));
    fprintf(md, "\nRatio worst / best: talk %.0f (\"about 2,500 times\"); library at the printed shininess "
                "500 and 10: %.0f; library at shininess 50 and 1: %.0f.\n",
            rows[0].result / rows[1].result, lib_ratio,
            (10.0 * 0.61 * ibl_blinn_phong_norm(50.0f)) / (0.04 * ibl_blinn_phong_norm(1.0f)));
    /* the float64 closed form agrees with the library's float pieces */
    double worst = 10.0 * schlick_d(0.04, 0.1) * triace_norm_d(500.0);
    fprintf(md, "Closed form in float64 at shininess 500: %.5g (library %.5g).\n", worst,
            10.0 * ibl_fresnel_schlick(0.04f, 0.1f) * ibl_blinn_phong_norm(500.0f));
}

/* What is left of the talk's worst case (n.E = E.H = 0.1: the mirror direction, h = n) after
 * multiplying by AO or by each specular occlusion formula. */
static void occlusion_table(FILE *md)
{
    static const ibl_so_formula formulas[] = {IBL_SO_AO, IBL_SO_TRIACE, IBL_SO_TRIACE_SHININESS,
                                              IBL_SO_TRIACE_FAST, IBL_SO_FROSTBITE, IBL_SO_CONE};
    static const float aos[] = {0.1f, 0.3f, 0.5f};
    double worst = rows[0].result;
    float s = 500.0f, r = ibl_roughness_from_shininess(s);
    fprintf(md, "\nThe talk's worst case (%.3f: grazing, n·E = 0.1, shininess 500) times the occlusion "
                "factor (`ibl_specular_occlusion`, n·E = 0.1, roughness %.3f for the formulas that take one):\n\n",
            worst, (double)r);
    fprintf(md, "| factor | AO = 0.1 | AO = 0.3 | AO = 0.5 |\n|---|---|---|---|\n");
    for (size_t i = 0; i < sizeof formulas / sizeof formulas[0]; i++) {
        fprintf(md, "| %s |", ibl_so_formula_name(formulas[i]));
        for (size_t j = 0; j < sizeof aos / sizeof aos[0]; j++) {
            float so = ibl_specular_occlusion(formulas[i], 0.1f, aos[j], r, s);
            fprintf(md, " %.4g × %.3f = %.4g |", worst, (double)so, worst * so);
        }
        fprintf(md, "\n");
    }
}

int study_artefact(const study_env *env)
{
    FILE *md = study_fragment(env, "artefact");
    if (!md) return 1;
    value_table(md);
    occlusion_table(md);
    return study_fragment_close(env, md, "artefact");
}
