/* Solves a scene image through the C ABI in a workspace this program allocates (exactly
 * the plan's suggestion), and writes the results table `hirad solve --results` writes, byte
 * for byte (with `--visibility core` for hr: hirad's command line casts hr's rays with
 * another BVH by default, whose rounding differs in the last digits):
 *
 *     embed [OPTIONS] SCENE.hirb [OUT.csv]
 *
 *     --brute-force        this file's own ray caster (every polygon tested for every ray:
 *                          small scenes only) instead of the core's BVH; implies --method hr
 *     --method hr|hi       as `hirad solve --method` (default: as it chooses)
 *     --instancing POLICY  all, auto, none or every:N, as `hirad solve --instancing`
 *
 * Without OUT.csv nothing is written: the run's figures go to stderr. The table is written
 * to OUT.csv.part and renamed when complete, so a failed run leaves no half-written table.
 * Exit status as `hirad solve`'s: 0 right, 1 written but not right, 2 usage, 3 the scene
 * is invalid, 4 failed.
 *
 * Built by CI with gcc -Wall -Wextra -Werror against the static library:
 *
 *     cargo build -p hirad-ffi
 *     gcc -Wall -Wextra -Werror -Iffi/include ffi/examples/embed.c \
 *         target/debug/libhirad_ffi.a -lpthread -ldl -lm -o embed
 */
#include "hirad.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the results table, written row by row from the polygon callback ---- */

typedef struct Table {
    FILE *out;       /* NULL: rows are counted, not written */
    int two_sided;   /* the table has back-side columns */
    uint64_t rows;
    int failed;      /* a write failed */
} Table;

static void put_float(FILE *out, float v) {
    char buf[64];
    if (hirad_format_float(v, buf, sizeof buf) < sizeof buf) {
        fputs(buf, out);
    }
}

/* A text field as hirad's tables quote it: quoted (with "" for a quote) when it holds a
 * comma, a quote, a line break, or leading or trailing spaces; line breaks as spaces. */
static void put_field(FILE *out, const char *text) {
    size_t n = strlen(text);
    int quote = strpbrk(text, ",\"\n\r") != NULL || (n > 0 && (text[0] == ' ' || text[n - 1] == ' '));
    if (!quote) {
        fputs(text, out);
        return;
    }
    fputc('"', out);
    for (const char *c = text; *c; c++) {
        if (*c == '"') {
            fputs("\"\"", out);
        } else if (*c == '\n' || *c == '\r') {
            fputc(' ', out);
        } else {
            fputc(*c, out);
        }
    }
    fputc('"', out);
}

static void put_values(FILE *out, const float *values, uint32_t bands) {
    for (uint32_t b = 0; b < bands; b++) {
        fputc(',', out);
        if (values) {
            put_float(out, values[b]);
        }
    }
}

static int32_t on_polygon(void *user, const HiradPolygon *p) {
    Table *t = ((void **)user)[0];
    t->rows++;
    if (!t->out) {
        return 0;
    }
    fprintf(t->out, "%" PRIu64 ",", p->id);
    put_float(t->out, p->area);
    put_values(t->out, p->radiosity, p->bands);
    put_values(t->out, p->irradiance, p->bands);
    if (t->two_sided) {
        put_values(t->out, p->radiosity_back, p->bands);
        put_values(t->out, p->irradiance_back, p->bands);
    }
    fputc(',', t->out);
    put_field(t->out, p->material_name ? p->material_name : "");
    fputc(',', t->out);
    put_field(t->out, p->group ? p->group : "");
    fputc('\n', t->out);
    if (ferror(t->out)) {
        t->failed = 1;
        return 1; /* stops the solve: HIRAD_STATUS_SINK_FAILED */
    }
    return 0;
}

/* ---- progress: one line per phase on stderr ---- */

static int32_t on_progress(void *user, const char *phase, uint64_t done, uint64_t total) {
    char *last = ((void **)user)[1];
    (void)done;
    (void)total;
    if (strncmp(last, phase, 255) != 0) {
        strncpy(last, phase, 255);
        last[255] = '\0';
        fprintf(stderr, "  %s\n", phase);
    }
    return 0; /* non-zero would cancel */
}

/* ---- a brute-force ray caster over the scene's world polygons ---- */

typedef struct Caster {
    HiradWorldPolygon *polygons;
    uint64_t count;
} Caster;

/* Crossings this near either end of a segment do not block it: the segment starts and ends
 * on surfaces (the core's BVH keeps the same margin). */
#define SEGMENT_MARGIN 1e-5

/* The segment parameter where from + t (to - from) crosses triangle a b c, t in
 * (SEGMENT_MARGIN, 1 - SEGMENT_MARGIN), or -1 (Moeller-Trumbore in double precision). */
static double crossing(const float *from, const float *to, const float *a, const float *b,
                       const float *c) {
    double d[3], e1[3], e2[3], s[3], p[3], q[3];
    for (int k = 0; k < 3; k++) {
        d[k] = (double)to[k] - from[k];
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
        s[k] = (double)from[k] - a[k];
    }
    p[0] = d[1] * e2[2] - d[2] * e2[1];
    p[1] = d[2] * e2[0] - d[0] * e2[2];
    p[2] = d[0] * e2[1] - d[1] * e2[0];
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0.0) {
        return -1.0;
    }
    double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
    if (u < 0.0 || u > 1.0) {
        return -1.0;
    }
    q[0] = s[1] * e1[2] - s[2] * e1[1];
    q[1] = s[2] * e1[0] - s[0] * e1[2];
    q[2] = s[0] * e1[1] - s[1] * e1[0];
    double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
    if (v < 0.0 || u + v > 1.0) {
        return -1.0;
    }
    double t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
    return (t > SEGMENT_MARGIN && t < 1.0 - SEGMENT_MARGIN) ? t : -1.0;
}

/* The nearest crossing of any polygon not in skip: its id in *hit, t returned (-1: none). */
static double nearest(const Caster *c, const float *from, const float *to, const uint32_t *skip,
                      uint32_t *hit, int first_only) {
    double best = -1.0;
    for (uint64_t i = 0; i < c->count; i++) {
        if (i == skip[0] || i == skip[1]) {
            continue;
        }
        const HiradWorldPolygon *p = &c->polygons[i];
        for (uint32_t k = 2; k < p->corners; k++) {
            double t = crossing(from, to, p->corner[0], p->corner[k - 1], p->corner[k]);
            if (t > 0.0 && (best < 0.0 || t < best)) {
                best = t;
                *hit = (uint32_t)i;
                if (first_only) {
                    return best;
                }
            }
        }
    }
    return best;
}

static float brute_transmittance(void *user, const float *from, const float *to,
                                 const uint32_t *skip) {
    uint32_t hit;
    return nearest(((void **)user)[2], from, to, skip, &hit, 1) < 0.0 ? 1.0f : 0.0f;
}

static int32_t brute_first_hit(void *user, const float *from, const float *to,
                               const uint32_t *skip, uint32_t *polygon, float *t) {
    double best = nearest(((void **)user)[2], from, to, skip, polygon, 0);
    if (best < 0.0) {
        return 0;
    }
    *t = (float)best;
    return 1;
}

/* ---- the program ---- */

static uint8_t *read_file(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        return NULL;
    }
    size_t cap = 1 << 16, n;
    uint8_t *bytes = malloc(cap);
    *len = 0;
    while (bytes && (n = fread(bytes + *len, 1, cap - *len, f)) > 0) {
        *len += n;
        if (*len == cap) {
            uint8_t *more = realloc(bytes, cap * 2);
            if (!more) {
                free(bytes);
                bytes = NULL;
                break;
            }
            bytes = more;
            cap *= 2;
        }
    }
    if (bytes && ferror(f)) {
        free(bytes);
        bytes = NULL;
    }
    fclose(f);
    return bytes;
}

/* The exit status of a failed call, as `hirad solve` classes its errors. */
static int exit_of(HiradStatus s) {
    switch (s) {
    case HIRAD_STATUS_NOT_RIGHT:
        return 1;
    case HIRAD_STATUS_INVALID_SETTINGS:
    case HIRAD_STATUS_WORKSPACE_TOO_SMALL:
        return 2;
    case HIRAD_STATUS_INVALID_SCENE:
    case HIRAD_STATUS_NOT_OPEN:
    case HIRAD_STATUS_NO_TABLES:
        return 3;
    default:
        return 4;
    }
}

static int usage(const char *program) {
    fprintf(stderr,
            "usage: %s [--brute-force] [--method hr|hi] [--instancing all|auto|none|every:N] "
            "SCENE.hirb [OUT.csv]\n",
            program);
    return 2;
}

int main(int argc, char **argv) {
    HiradSettings settings;
    hirad_settings_default(&settings);
    int brute = 0, arg = 1;
    for (; arg < argc && strncmp(argv[arg], "--", 2) == 0; arg++) {
        const char *value = arg + 1 < argc ? argv[arg + 1] : "";
        if (strcmp(argv[arg], "--brute-force") == 0) {
            brute = 1;
        } else if (strcmp(argv[arg], "--method") == 0 && strcmp(value, "hr") == 0) {
            settings.method = HIRAD_METHOD_HR;
            arg++;
        } else if (strcmp(argv[arg], "--method") == 0 && strcmp(value, "hi") == 0) {
            settings.method = HIRAD_METHOD_HI;
            arg++;
        } else if (strcmp(argv[arg], "--instancing") == 0) {
            unsigned n;
            char rest;
            if (strcmp(value, "all") == 0) {
                settings.instancing = HIRAD_INSTANCING_ALL;
            } else if (strcmp(value, "auto") == 0) {
                settings.instancing = HIRAD_INSTANCING_AUTO;
            } else if (strcmp(value, "none") == 0) {
                settings.instancing = HIRAD_INSTANCING_NONE;
            } else if (sscanf(value, "every:%u%c", &n, &rest) == 1 && n > 0) {
                settings.instancing = HIRAD_INSTANCING_EVERY;
                settings.instancing_every = n;
            } else {
                return usage(argv[0]);
            }
            arg++;
        } else {
            return usage(argv[0]);
        }
    }
    if (argc - arg < 1 || argc - arg > 2) {
        return usage(argv[0]);
    }
    const char *path = argv[arg];
    const char *out_path = argc - arg == 2 ? argv[arg + 1] : NULL;
    size_t len;
    uint8_t *bytes = read_file(path, &len);
    if (!bytes) {
        perror(path);
        return 3;
    }
    HiradScene *scene = NULL;
    HiradStatus status = hirad_scene_open_memory(bytes, len, &scene);
    free(bytes); /* the handle keeps its own copy */
    if (status != HIRAD_STATUS_OK) {
        fprintf(stderr, "%s: %s\n", path, scene ? hirad_scene_message(scene) : "out of memory");
        hirad_scene_free(scene);
        return 3;
    }

    Table table = {0};
    char phase[256] = "";
    Caster caster = {0};
    void *user[3] = {&table, phase, &caster};
    HiradCallbacks callbacks = {0};
    callbacks.user = user;
    callbacks.progress = on_progress;
    callbacks.polygon = on_polygon;
    callbacks.labels = out_path != NULL;
    int code = 0;
    char *part = NULL;
    void *workspace = NULL;

    if (brute) {
        HiradSceneInfo info;
        status = hirad_scene_info(scene, &info);
        if (status == HIRAD_STATUS_OK) {
            caster.count = info.expanded_polygons;
            caster.polygons = malloc(sizeof(HiradWorldPolygon) * (caster.count ? caster.count : 1));
            status = caster.polygons ? hirad_scene_world_polygons(scene, caster.polygons, caster.count)
                                     : HIRAD_STATUS_OUT_OF_MEMORY;
        }
        if (status != HIRAD_STATUS_OK) {
            fprintf(stderr, "%s: %s\n", path, hirad_scene_message(scene));
            code = exit_of(status);
            goto done;
        }
        settings.method = HIRAD_METHOD_HR; /* a caller's caster serves hr */
        callbacks.transmittance = brute_transmittance;
        callbacks.first_hit = brute_first_hit;
    }

    HiradPlan plan;
    status = hirad_plan(scene, &settings, &callbacks, &plan);
    if (status != HIRAD_STATUS_OK) {
        fprintf(stderr, "%s: %s\n", path, hirad_scene_message(scene));
        code = exit_of(status);
        goto done;
    }
    fprintf(stderr, "%s: method %s, workspace %" PRIu64 " bytes (least %" PRIu64 ")\n", path,
            plan.method == HIRAD_METHOD_HI ? "hi" : "hr", plan.suggested_bytes, plan.min_bytes);
    workspace = malloc(plan.suggested_bytes);
    if (!workspace) {
        fprintf(stderr, "%s: cannot allocate a workspace of %" PRIu64 " bytes\n", path,
                plan.suggested_bytes);
        code = 4;
        goto done;
    }

    if (out_path) {
        const char *header;
        uint32_t two_sided;
        status = hirad_scene_results_header(scene, &header, &two_sided);
        if (status != HIRAD_STATUS_OK) {
            fprintf(stderr, "%s: %s\n", path, hirad_scene_message(scene));
            code = exit_of(status);
            goto done;
        }
        part = malloc(strlen(out_path) + 6);
        if (!part) {
            code = 4;
            goto done;
        }
        sprintf(part, "%s.part", out_path);
        table.out = fopen(part, "wb");
        if (!table.out) {
            perror(part);
            code = 2;
            goto done;
        }
        table.two_sided = (int)two_sided;
        fprintf(table.out, "%s\n", header);
    }

    HiradStats stats;
    status = hirad_solve(scene, &settings, workspace, plan.suggested_bytes, &callbacks, &stats);
    if (status == HIRAD_STATUS_OK || status == HIRAD_STATUS_NOT_RIGHT) {
        fprintf(stderr, "%" PRIu64 " polygons, %" PRIu64 " elements, %" PRIu64 " links, %.2f s\n",
                stats.polygons, stats.elements, stats.links, stats.seconds);
        for (uint32_t b = 0; b < stats.bands; b++) {
            fprintf(stderr, "  band %" PRIu32 ": in %.6f W, absorbed %.6f W, escaped %.6f W, imbalance %+.3f %%\n",
                    b, stats.emitted[b] + stats.direct[b], stats.absorbed[b] + stats.absorbed_backs[b],
                    stats.escaped[b], stats.imbalance_percent[b]);
        }
    }
    if (status != HIRAD_STATUS_OK) {
        fprintf(stderr, "%s: %s\n", path, hirad_scene_message(scene));
        code = exit_of(status);
    }
    if (table.out) {
        int closed = fclose(table.out);
        table.out = NULL;
        int written = closed == 0 && !table.failed && (code == 0 || code == 1);
        if (written && rename(part, out_path) == 0) {
            fprintf(stderr, "wrote %s (%" PRIu64 " rows)\n", out_path, table.rows);
        } else {
            if (code == 0 || code == 1) {
                fprintf(stderr, "%s: could not be written\n", out_path);
                code = 4;
            }
            remove(part);
        }
    }

done:
    if (table.out) {
        fclose(table.out);
        remove(part);
    }
    free(part);
    free(workspace);
    free(caster.polygons);
    hirad_scene_free(scene);
    return code;
}
