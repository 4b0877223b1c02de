// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia prep SCENE.json -o MODEL.h5`: runs the preprocessing stages of
// prep/ one by one with progress on stderr, times each step and its
// peak memory, writes the model (atomically: no partial file on error) and
// an optional ParaView preview, and ends with a summary, as text on stderr or
// (--json) as one JSON object on stdout. Built as the module fascia-prep.so,
// which the program loads when the command is asked for (prep_module.c).
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <math.h>
#include <unistd.h>

#include "commands.h"
#include "fascia/fascia.h"
#include "fascia/prep.h"

enum { STEP_MAX = 12 };

typedef struct step_clock {
  int count;
  const char *name[STEP_MAX];
  double seconds[STEP_MAX];
  double peak_bytes[STEP_MAX];
  double started;
  int resettable; ///< /proc/self/clear_refs resets the peak: peaks are per step
} step_clock;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

// Peak resident memory (bytes) since the last reset (VmHWM), else since start.
static double peak_bytes(void) {
  FILE *f = fopen("/proc/self/status", "r");
  if (f) {
    char line[256];
    while (fgets(line, sizeof line, f))
      if (!strncmp(line, "VmHWM:", 6)) {
        fclose(f);
        return 1024.0 * atof(line + 6);
      }
    fclose(f);
  }
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return 1024.0 * (double)ru.ru_maxrss;
}

static int reset_peak(void) {
  FILE *f = fopen("/proc/self/clear_refs", "w");
  if (!f) return 0;
  const int ok = fputs("5", f) >= 0;
  return fclose(f) == 0 && ok;
}

static void step_begin(step_clock *c) {
  c->resettable = reset_peak();
  c->started = now();
}

static void step_end(step_clock *c, const char *name) {
  if (c->count >= STEP_MAX) return;
  c->name[c->count] = name;
  c->seconds[c->count] = now() - c->started;
  c->peak_bytes[c->count] = peak_bytes();
  c->count++;
}

typedef fascia_prep_stages prep_run; // every stage's output

enum { GAP_NONE, GAP_OVERLAP, GAP_CONTACT, GAP_THIN, GAP_OPEN };

// What lies between organs a and b: not measured, an overlap, a contact
// (surfaces closer than a tenth of a voxel, which no voxel centre can lie
// between), a real gap thinner than three
// voxels between two organs of one tissue (a warning: the tissue across it
// has fewer than three voxels), or a gap.
static int gap_kind(const prep_run *r, int32_t a, int32_t b) {
  const fascia_prep_volume *v = r->volume;
  const double d = v->closest[a * v->organ_count + b], h = v->voxel_size;
  if (d < 0) return GAP_NONE;
  for (int32_t k = 0; k < v->overlap_count; ++k)
    if ((v->overlaps[k].a == a && v->overlaps[k].b == b) || (v->overlaps[k].a == b && v->overlaps[k].b == a))
      return GAP_OVERLAP;
  if (d < 0.1 * h) return GAP_CONTACT;
  if (d >= 3 * h * (1 - 1e-6)) return GAP_OPEN; // three voxels up to the round-off of mesh files
  for (int32_t t = 0; t < r->scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = r->scene->tissues + t;
    int found = 0;
    for (int32_t k = 0; k < td->organ_count; ++k) found += td->organs[k] == a || td->organs[k] == b;
    if (found == 2) return GAP_THIN;
  }
  return GAP_OPEN;
}

// The warning of a GAP_THIN pair, naming the scene file.
static void thin_gap_warning(const prep_run *r, int32_t a, int32_t b, char *line, size_t size) {
  const fascia_prep_volume *v = r->volume;
  const double d = v->closest[a * v->organ_count + b];
  snprintf(line, size,
           "the gap between '%s' and '%s' (%.3g mm) is thinner than three voxels of %.3g mm: the tissue across it "
           "is poorly resolved; set voxel_size (scene '%s') to %.3g m or less",
           r->meshes->organs[a].name, r->meshes->organs[b].name, 1e3 * d, 1e3 * v->voxel_size, r->scene->path, d / 3);
}

// How tissue t is held: its frames, the free ones (simulated), and per
// organ [organ_count] the frames it shares with it and, for organs it
// touches but does not connect, the frames on them left free by its
// coupling rules (touched_free). Returns the free count.
typedef struct tissue_hold {
  int32_t frames, free;
  int32_t *shared, *touched_free; ///< [organ_count]
} tissue_hold;

static int tissue_hold_count(const prep_run *r, int32_t t, tissue_hold *hold) {
  const int32_t organs = r->meshes->count;
  memset(hold, 0, sizeof *hold);
  hold->shared = calloc((size_t)organs + 1, sizeof *hold->shared);
  hold->touched_free = calloc((size_t)organs + 1, sizeof *hold->touched_free);
  if (!hold->shared || !hold->touched_free) return 0;
  const fascia_prep_points *p = r->points;
  uint8_t *shared = calloc((size_t)p->frame_count + 1, 1);
  if (!shared) return 0;
  for (int32_t c = 0; c < r->coupling->count; ++c)
    if (p->frame_tissue[r->coupling->frame[c]] == t) {
      hold->shared[r->coupling->organ[c]]++;
      shared[r->coupling->frame[c]] = 1;
    }
  for (int32_t i = 0; i < p->frame_count; ++i) {
    if (p->frame_tissue[i] != t) continue;
    hold->frames++;
    if (shared[i]) continue;
    hold->free++;
    if (p->frame_organ[i] >= 0) hold->touched_free[p->frame_organ[i]]++; // on an organ, left free by the rules
  }
  free(shared);
  return 1;
}

static void tissue_hold_free(tissue_hold *hold) {
  free(hold->shared), free(hold->touched_free);
  hold->shared = hold->touched_free = NULL;
}

// The warning when tissue t has no free frame: every frame moves with an
// organ, so the tissue carries no deformation of its own.
static void no_free_frame_warning(const prep_run *r, int32_t t, int32_t frames, char *line, size_t size) {
  const fascia_prep_tissue_def *td = r->scene->tissues + t;
  if (td->form != FASCIA_PREP_FORM_VOLUME) {
    snprintf(line, size,
             "tissue '%s' (%s) has no free frame: all %d of its frames are shared with organs and move with them, so "
             "nothing of it is simulated; %s (scene '%s')",
             td->name, fascia_prep_form_name(td->form), (int)frames,
             td->form == FASCIA_PREP_FORM_STRAND ? "lower its frame_spacing below its length"
                                                  : "refine its mesh away from the organs, or lower coupling.tolerance",
             r->scene->path);
    return;
  }
  snprintf(line, size,
           "tissue '%s' has no free frame: all %d of its frames lie on organ surfaces and move with them, so nothing "
           "of it is simulated (its gaps are thinner than about twice the coupling tolerance, %.3g mm, plus a "
           "voxel); lower voxel_size and coupling.tolerance (scene '%s')",
           td->name, (int)frames, 1e3 * td->coupling_tolerance, r->scene->path);
}

// The warning when volume tissue t's frames are farther apart than half its
// layers (its provenance's half_layer_spacing, prep's package.c: only where
// the material resists a change of volume). 0 when it does not apply.
static int coarse_frames_warning(const prep_run *r, int32_t t, char *line, size_t size) {
  const fascia_prep_tissue_def *td = r->scene->tissues + t;
  cJSON *prov = r->model->provenance ? cJSON_Parse(r->model->provenance) : NULL;
  const cJSON *tissues = cJSON_GetObjectItem(cJSON_GetObjectItem(prov, "parameters"), "tissues");
  const cJSON *entry = cJSON_GetArrayItem(tissues, t);
  const double half_layer = cJSON_GetNumberValue(cJSON_GetObjectItem(entry, "half_layer_spacing"));
  const double depth = cJSON_GetNumberValue(cJSON_GetObjectItem(entry, "mean_depth"));
  cJSON_Delete(prov);
  if (!(half_layer > 0 && td->frame_spacing > half_layer)) return 0;
  snprintf(line, size,
           "tissue '%s': frames %.3g mm apart across layers about %.3g mm thick (four times its mean depth, %.3g mm) "
           "at Poisson ratio %.2g: its organ forces may be far from converged until the frames are about half a "
           "layer apart (frame_spacing %.2g mm or less; docs/mechanics.md, \"Thin layers: held by both faces\"); "
           "fascia tradeoff measures how far (scene '%s')",
           td->name, 1e3 * td->frame_spacing, 2e3 * half_layer, 1e3 * depth,
           r->scene->materials[td->material].poisson_ratio, 1e3 * half_layer, r->scene->path);
  return 1;
}

// 1 when all of volume tissue t lies in layers held by their faces (a
// tissue with no free frame that is nonetheless simulated as it should be).
static int held_layer_only(const prep_run *r, int32_t t) {
  const double held = r->points->tissue_held_layer_volume[t];
  return r->scene->tissues[t].form == FASCIA_PREP_FORM_VOLUME && held > 0 &&
         held >= FASCIA_PREP_HELD_LAYER_SHARE * r->volume->tissues[t].volume;
}

// Sizes import found off anatomy's (fascia_prep_meshes.warnings).
static void print_warnings(const fascia_prep_meshes *meshes) {
  for (int32_t k = 0; meshes && k < meshes->warning_count; ++k) fprintf(stderr, "warning: %s\n", meshes->warnings[k]);
}

static void print_summary(const prep_run *r, const step_clock *c, const char *output, const char *preview) {
  const fascia_prep_scene *sc = r->scene;
  const fascia_prep_volume *v = r->volume;
  const double h = v->voxel_size;
  fprintf(stderr, "\nfascia prep: %s -> %s\n", sc->path, output);
  print_warnings(r->meshes);
  for (int32_t k = 0; k < sc->absent_organ_count; ++k) // "optional": true organs the segmentation lacks
    fprintf(stderr, "optional organ '%s': not in the label map, left out\n", sc->absent_organs[k]);
  for (int32_t k = 0; k < sc->dropped_tissue_count; ++k)
    fprintf(stderr, "tissue '%s': left out with the optional organs the label map lacks\n", sc->dropped_tissues[k]);
  fprintf(stderr, "organs\n");
  for (int32_t o = 0; o < r->meshes->count; ++o) {
    const fascia_prep_mesh *m = r->meshes->organs + o;
    const fascia_prep_mesh_report *p = &m->report;
    fprintf(stderr, "  %-16s %d parts, %d vertices, %d triangles; %d shared frames\n", m->name, (int)p->parts_used,
            (int)m->vertex_count, (int)m->triangle_count, (int)r->coupling->per_organ[o]);
    fprintf(stderr,
            "    repair: %d duplicate vertices merged, %d degenerate and %d duplicate faces removed, %d pinched "
            "vertices split, %d of %d components reoriented, %d holes filled, %d left (%d border edges), %d "
            "self-intersecting face pairs\n",
            (int)p->duplicate_vertices_merged, (int)p->degenerate_faces_removed, (int)p->duplicate_faces_removed,
            (int)p->nonmanifold_vertices_split, (int)p->components_reoriented, (int)p->components,
            (int)p->holes_filled, (int)p->holes_left, (int)p->border_edges, (int)p->self_intersections);
    if (p->inside_rule[0])
      fprintf(stderr, "    inside: %s; %.4g cm^3\n", p->inside_rule, 1e6 * p->enclosed_volume);
  }
  for (int32_t k = 0; k < v->overlap_count; ++k)
    fprintf(stderr, "overlap: '%s' and '%s' share %.4g cm^3, up to %.3g mm deep (rule: tissue outside both)\n",
            r->meshes->organs[v->overlaps[k].a].name, r->meshes->organs[v->overlaps[k].b].name,
            1e6 * v->overlaps[k].volume, 1e3 * v->overlaps[k].depth);
  for (int32_t a = 0; a < v->organ_count; ++a)
    for (int32_t b = a + 1; b < v->organ_count; ++b) {
      const double d = v->closest[a * v->organ_count + b];
      const char *na = r->meshes->organs[a].name, *nb = r->meshes->organs[b].name;
      switch (gap_kind(r, a, b)) {
      case GAP_NONE:
      case GAP_OVERLAP: break;
      case GAP_CONTACT:
        fprintf(stderr,
                "contact: '%s' and '%s' touch (%.3g mm at the closest, on the surfaces): the tissue bridges the space "
                "around the contact where their surfaces are at most max_gap apart\n",
                na, nb, 1e3 * d);
        break;
      case GAP_THIN:
        fprintf(stderr, "gap: '%s' to '%s' %.3g mm at the closest (on the surfaces)\n", na, nb, 1e3 * d);
        {
          char line[512];
          thin_gap_warning(r, a, b, line, sizeof line);
          fprintf(stderr, "warning: %s\n", line);
        }
        break;
      case GAP_OPEN: fprintf(stderr, "gap: '%s' to '%s' %.3g mm at the closest (on the surfaces)\n", na, nb, 1e3 * d);
      }
    }
  for (int32_t k = 0; k < r->meshes->contact_count; ++k) {
    const fascia_prep_label_contact *lc = r->meshes->contacts + k;
    fprintf(stderr,
            "labels touch: '%s' and '%s' share %lld voxel faces (%.4g cm^2) in the label map; %s\n",
            r->meshes->organs[lc->a].name, r->meshes->organs[lc->b].name, (long long)lc->faces, 1e4 * lc->area,
            lc->layer > 0 ? "each gave up half the interface layer there" : "no interface layer: no tissue between them there");
  }
  int64_t voxels = 0;
  for (int32_t t = 0; t < sc->tissue_count; ++t) {
    const fascia_prep_tissue_report *tr = v->tissues + t;
    int32_t frames = 0, samples = 0;
    double sample_volume = 0;
    for (int32_t i = 0; i < r->points->frame_count; ++i) frames += r->points->frame_tissue[i] == t;
    for (int32_t s = 0; s < r->points->sample_count; ++s)
      if (r->points->sample_tissue[s] == t) // a sheet's drilling stabiliser repeats the volume of others
        ++samples, sample_volume += r->points->sample_drilling[s] ? 0 : r->points->sample_volume[s];
    voxels += tr->voxels;
    const fascia_prep_tissue_def *tdef = sc->tissues + t;
    if (tdef->form == FASCIA_PREP_FORM_STRAND)
      fprintf(stderr,
              "tissue '%s': strand from '%s' to '%s', %s, %.4g mm long, section %.4g mm^2 (radius %.3g mm), "
              "%.4g cm^3 (samples: length x area%s); %d frames, %d samples\n",
              tdef->name, sc->organs[tdef->from.organ].name, sc->organs[tdef->to.organ].name,
              tdef->through_count ? "curved" : "straight",
              1e3 * sample_volume / tdef->area, 1e6 * tdef->area, 1e3 * tdef->radius, 1e6 * sample_volume,
              tdef->from.spread || tdef->to.spread ? ", its ends' fibres included" : "", (int)frames, (int)samples);
    else if (tdef->form == FASCIA_PREP_FORM_SHEET)
      fprintf(stderr,
              "tissue '%s': sheet '%s', %.4g cm^2 x thickness %.3g mm, %.4g cm^3 (samples: area x thickness); %d "
              "frames (the mesh's vertices), %d samples\n",
              tdef->name, tdef->mesh, 1e4 * sample_volume / tdef->thickness, 1e3 * tdef->thickness,
              1e6 * sample_volume, (int)frames, (int)samples);
    else
      fprintf(stderr,
              "tissue '%s': %lld voxels of %.3g mm, %.4g cm^3 in %d piece(s) (%d smaller pieces, %.3g cm^3, dropped); "
              "%d frames, %d samples\n",
              sc->tissues[t].name, (long long)tr->voxels, 1e3 * h, 1e6 * tr->volume, (int)tr->components,
              (int)tr->dropped_components, 1e6 * tr->dropped_volume, (int)frames, (int)samples);
    if (tdef->form == FASCIA_PREP_FORM_VOLUME && tr->slide_volume > 0)
      fprintf(stderr, "  %.3g cm^3 between its organs left out where they are closer than min_gap %.3g mm: they slide "
                      "on each other there\n",
              1e6 * tr->slide_volume, 1e3 * tdef->min_gap);
    tissue_hold hold;
    if (tissue_hold_count(r, t, &hold)) {
      const int32_t mid_layer = r->points->tissue_mid_layer_frames[t];
      char layer[96] = "";
      if (mid_layer > 0) snprintf(layer, sizeof layer, " (%d on the mid-layers of gaps thinner than its frame spacing)", (int)mid_layer);
      fprintf(stderr, "  form %s; %d free frames%s; shared with", fascia_prep_form_name(tdef->form), (int)hold.free, layer);
      int printed = 0;
      for (int32_t o = 0; o < r->meshes->count; ++o)
        if (hold.shared[o] && fascia_prep_tissue_connects(sc->tissues + t, o))
          fprintf(stderr, "%s %s %d", printed++ ? "," : "", r->meshes->organs[o].name, (int)hold.shared[o]);
      fprintf(stderr, "%s\n", printed ? "" : " no organ");
      const double held = r->points->tissue_held_layer_volume[t];
      if (held > 0)
        fprintf(stderr,
                "  %.3g cm^3 (%.0f %%) in gaps thinner than two sample spacings (%.3g mm): layers held by frames on "
                "both faces, about a gap apart, with no free frame of their own\n",
                1e6 * held, 100 * held / fmax(tr->volume, held), 2e3 * tdef->sample_spacing);
      for (int32_t o = 0; o < r->meshes->count; ++o) {
        if (fascia_prep_tissue_connects(sc->tissues + t, o) || (!hold.shared[o] && !hold.touched_free[o])) continue;
        if (hold.shared[o])
          fprintf(stderr, "  also touches '%s', which it does not connect: %d frames shared with it (scene key "
                          "tissues[%d].coupling.others: false, or coupling.organs.%s: false, leaves them free)\n",
                  r->meshes->organs[o].name, (int)hold.shared[o], (int)t, r->meshes->organs[o].name);
        else
          fprintf(stderr, "  also touches '%s', which it does not connect: its %d frames there left free\n",
                  r->meshes->organs[o].name, (int)hold.touched_free[o]);
      }
      if (hold.frames > 0 && hold.free == 0 && !held_layer_only(r, t)) {
        char line[768];
        no_free_frame_warning(r, t, hold.frames, line, sizeof line);
        fprintf(stderr, "warning: %s\n", line);
      }
    }
    tissue_hold_free(&hold);
    char coarse[768];
    if (coarse_frames_warning(r, t, coarse, sizeof coarse)) fprintf(stderr, "warning: %s\n", coarse);
    if (sc->tissues[t].organ_count > 2 && tdef->form == FASCIA_PREP_FORM_VOLUME) {
      fprintf(stderr, "  by the organs each voxel bridges:");
      const fascia_prep_tissue_def *td = sc->tissues + t;
      int printed = 0;
      for (int32_t i = 0, p = 0; i < td->organ_count; ++i)
        for (int32_t j = i + 1; j < td->organ_count; ++j, ++p)
          if (tr->pair_volume[p] > 0)
            fprintf(stderr, "%s %s-%s %.3g cm^3", printed++ ? "," : "", sc->organs[td->organs[i]].name,
                    sc->organs[td->organs[j]].name, 1e6 * tr->pair_volume[p]);
      fprintf(stderr, "\n");
    }
    if (tr->occupied_volume > 0) {
      char labels[512];
      fascia_prep_occupied_text(sc, tr, labels, sizeof labels);
      fprintf(stderr, "  %.3g cm^3 between its organs left out, occupied by labels the scene does not model: %s (to "
                      "let tissue take them, list them in segmentation.connective)\n",
              1e6 * tr->occupied_volume, labels);
    }
    if (sc->tissues[t].shape_kind == FASCIA_PREP_SHAPE_TET)
      fprintf(stderr, "  tet: %d tetrahedra kept inside the region, %.4g cm^3 (%.1f %% of its voxels); the samples, "
                      "%d per tet, add up to the tetrahedra's volume\n",
              (int)(samples / sc->tissues[t].samples_per_tet), 1e6 * sample_volume,
              tr->volume > 0 ? 100 * sample_volume / tr->volume : 0, (int)sc->tissues[t].samples_per_tet);
  }
  // a deformable organ's own frames and samples (beside the tissue frames it shares)
  for (int32_t o = 0; o < sc->organ_count; ++o) {
    if (sc->organs[o].kind != FASCIA_ORGAN_DEFORMABLE) continue;
    const fascia_prep_tissue_report *dr = v->organ_regions + o;
    int32_t frames = 0, samples = 0;
    for (int32_t i = 0; i < r->points->frame_count; ++i) frames += r->points->frame_inside_organ[i] == o;
    double wall = 0; // a shell's samples carry its wall, area x thickness
    for (int32_t s = 0; s < r->points->sample_count; ++s)
      if (r->points->sample_inside_organ[s] == o) ++samples, wall += r->points->sample_volume[s];
    if (sc->organs[o].shell) {
      fprintf(stderr,
              "shell organ '%s': wall %.3g mm thick, %.4g cm^2; %d frames of its own and %d shared with tissues, "
              "%d samples\n",
              sc->organs[o].name, 1e3 * sc->organs[o].thickness, 1e4 * wall / sc->organs[o].thickness, (int)frames,
              (int)r->coupling->per_organ[o], (int)samples);
      continue;
    }
    fprintf(stderr,
            "deformable organ '%s': %lld voxels of %.3g mm, %.4g cm^3 in %d piece(s) (%d smaller pieces, %.3g cm^3, "
            "dropped); %d frames of its own and %d shared with tissues, %d samples\n",
            sc->organs[o].name, (long long)dr->voxels, 1e3 * h, 1e6 * dr->volume, (int)dr->components,
            (int)dr->dropped_components, 1e6 * dr->dropped_volume, (int)frames, (int)r->coupling->per_organ[o],
            (int)samples);
  }
  cJSON *prov = r->model->provenance ? cJSON_Parse(r->model->provenance) : NULL;
  const cJSON *dropped = cJSON_GetObjectItem(cJSON_GetObjectItem(prov, "reports"), "unheld_pieces_dropped");
  const cJSON *e;
  cJSON_ArrayForEach(e, dropped) {
    const cJSON *t = cJSON_GetObjectItem(e, "tissue"), *o = cJSON_GetObjectItem(e, "organ");
    const cJSON *x = cJSON_GetObjectItem(e, "position_m");
    const int held_at = (int)cJSON_GetNumberValue(cJSON_GetObjectItem(e, "held_at"));
    char why[160] = "that nothing holds (no fixed or prescribed organ, directly or through other tissue or organs)";
    if (held_at > 0) // a hinge: docs/organs.md
      snprintf(why, sizeof why, "held at only %d frame%s, about which it would turn at no cost (lower frame_spacing "
               "to keep it)", held_at, held_at > 1 ? "s, on a line" : "");
    fprintf(stderr, "dropped: a piece of %s '%s' %s: %.3g cm^3, %d frames, %d samples, near (%.4g, %.4g, %.4g) m\n",
            cJSON_IsString(t) ? "tissue" : "organ",
            cJSON_IsString(t) ? t->valuestring : cJSON_IsString(o) ? o->valuestring : "?", why,
            1e6 * cJSON_GetNumberValue(cJSON_GetObjectItem(e, "volume_m3")),
            (int)cJSON_GetNumberValue(cJSON_GetObjectItem(e, "frames")),
            (int)cJSON_GetNumberValue(cJSON_GetObjectItem(e, "samples")), cJSON_GetNumberValue(cJSON_GetArrayItem(x, 0)),
            cJSON_GetNumberValue(cJSON_GetArrayItem(x, 1)), cJSON_GetNumberValue(cJSON_GetArrayItem(x, 2)));
  }
  cJSON_Delete(prov);
  const double tissue_volume = fascia_model_tissue_volume(r->model);
  const double organ_volume = fascia_model_volume(r->model) - tissue_volume;
  char organs_part[96] = "";
  if (organ_volume > 0) snprintf(organs_part, sizeof organs_part, " (+ %.6g m^3 of deformable organs)", organ_volume);
  fprintf(stderr, "model: %d frames (%d shared), %d samples, %d pairs, tissue volume %.6g m^3%s, linear reproduction "
                  "error %.2g m\n",
          (int)r->model->frame_count, (int)r->coupling->count, (int)r->model->sample_count,
          (int)r->model->pair_count, tissue_volume, organs_part, r->weights->max_linear_error);
  int32_t patched = 0;
  const int32_t patches = fascia_model_patch_count(r->model, &patched);
  if (patches > 0)
    fprintf(stderr, "volumetric patches: %d over %d samples (mean dilatation from Poisson ratio %.2g on; patch_radius "
                    "in the scene, docs/mechanics.md)\n",
            (int)patches, (int)patched, FASCIA_PATCH_MIN_POISSON);
  else
    fprintf(stderr, "volumetric patches: none (every material's Poisson ratio is below %.2g, patch_radius is 0, or "
                    "the frames are fine for the layer's depth, docs/mechanics.md; strands and sheets have none)\n",
            FASCIA_PATCH_MIN_POISSON);
  if (preview)
    fprintf(stderr, "preview: open %s/preview.pvd in ParaView (the organs, region, frames, samples, coupling; strands "
                    "and sheets)\n",
            preview);
  double total = 0;
  fprintf(stderr, "steps (peak resident memory %s)\n", c->resettable ? "per step" : "since start");
  for (int k = 0; k < c->count; ++k) {
    fprintf(stderr, "  %-16s %8.2f s  %8.1f MB\n", c->name[k], c->seconds[k], c->peak_bytes[k] / 1048576.0);
    total += c->seconds[k];
  }
  fprintf(stderr, "  %-16s %8.2f s\n", "total", total);
}

// The space between a tissue's organs that unmodelled labels occupy: total and per label.
static void occupied_json(cJSON *tissue, const fascia_prep_scene *scene, const fascia_prep_tissue_report *report) {
  cJSON_AddNumberToObject(tissue, "occupied_volume", report->occupied_volume);
  cJSON *labels = cJSON_AddArrayToObject(tissue, "occupied_by");
  for (int k = 0; k < 4 && report->occupied_labels[k]; ++k) {
    cJSON *e = cJSON_CreateObject();
    cJSON_AddNumberToObject(e, "label", report->occupied_labels[k]);
    const char *name = fascia_prep_label_name(&scene->segmentation, report->occupied_labels[k]);
    if (name) cJSON_AddStringToObject(e, "name", name);
    cJSON_AddNumberToObject(e, "volume", report->occupied_label_volume[k]);
    cJSON_AddItemToArray(labels, e);
  }
}

static void print_json(const prep_run *r, const step_clock *c, const char *output, const char *preview) {
  cJSON *root = cJSON_CreateObject();
  const fascia_prep_volume *v = r->volume;
  cJSON_AddStringToObject(root, "scene", r->scene->path);
  cJSON_AddStringToObject(root, "output", output);
  if (preview) cJSON_AddStringToObject(root, "preview", preview);
  cJSON_AddNumberToObject(root, "frames", r->model->frame_count);
  cJSON_AddNumberToObject(root, "samples", r->model->sample_count);
  int32_t patched = 0;
  cJSON_AddNumberToObject(root, "volumetric_patches", fascia_model_patch_count(r->model, &patched));
  cJSON_AddNumberToObject(root, "patched_samples", patched);
  cJSON_AddNumberToObject(root, "pairs", r->model->pair_count);
  cJSON_AddNumberToObject(root, "tissue_volume", fascia_model_tissue_volume(r->model));
  cJSON_AddNumberToObject(root, "volume", fascia_model_volume(r->model));
  cJSON_AddNumberToObject(root, "voxel_size", v->voxel_size);
  int64_t voxels = 0;
  for (int32_t t = 0; t < v->tissue_count; ++t) voxels += v->tissues[t].voxels;
  cJSON_AddNumberToObject(root, "voxels", (double)voxels);
  cJSON_AddNumberToObject(root, "coupling_frames", r->coupling->count);
  cJSON *coupling = cJSON_AddObjectToObject(root, "coupling");
  for (int32_t o = 0; o < r->meshes->count; ++o)
    cJSON_AddNumberToObject(coupling, r->meshes->organs[o].name, r->coupling->per_organ[o]);
  cJSON_AddNumberToObject(root, "max_linear_reproduction_error", r->weights->max_linear_error);
  cJSON *absent = cJSON_AddArrayToObject(root, "absent_organs"), *left_out = cJSON_AddArrayToObject(root, "dropped_tissues");
  for (int32_t k = 0; k < r->scene->absent_organ_count; ++k)
    cJSON_AddItemToArray(absent, cJSON_CreateString(r->scene->absent_organs[k]));
  for (int32_t k = 0; k < r->scene->dropped_tissue_count; ++k)
    cJSON_AddItemToArray(left_out, cJSON_CreateString(r->scene->dropped_tissues[k]));
  // pieces that nothing held, dropped by prep (its provenance lists them)
  cJSON *prov = r->model->provenance ? cJSON_Parse(r->model->provenance) : NULL;
  cJSON *dropped = cJSON_DetachItemFromObject(cJSON_GetObjectItem(prov, "reports"), "unheld_pieces_dropped");
  cJSON_AddItemToObject(root, "unheld_pieces_dropped", dropped ? dropped : cJSON_CreateArray());
  cJSON_Delete(prov);
  cJSON *warnings = cJSON_AddArrayToObject(root, "warnings"); // the meshes' first, then the tissues'
  for (int32_t k = 0; k < r->meshes->warning_count; ++k)
    cJSON_AddItemToArray(warnings, cJSON_CreateString(r->meshes->warnings[k]));
  cJSON *tissues = cJSON_AddArrayToObject(root, "tissues");
  for (int32_t t = 0; t < v->tissue_count; ++t) {
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "name", r->scene->tissues[t].name);
    cJSON_AddNumberToObject(e, "voxels", (double)v->tissues[t].voxels);
    cJSON_AddNumberToObject(e, "volume", v->tissues[t].volume);
    cJSON_AddNumberToObject(e, "components", v->tissues[t].components);
    cJSON_AddNumberToObject(e, "dropped_volume", v->tissues[t].dropped_volume);
    cJSON_AddNumberToObject(e, "slide_volume", v->tissues[t].slide_volume);
    cJSON_AddNumberToObject(e, "organ_face_voxels", (double)v->tissues[t].organ_face_voxels);
    cJSON *pairs = cJSON_AddArrayToObject(e, "pairs"); // the volume each pair of its organs bridges
    const fascia_prep_tissue_def *td = r->scene->tissues + t;
    for (int32_t i = 0, p = 0; td->form == FASCIA_PREP_FORM_VOLUME && i < td->organ_count; ++i)
      for (int32_t j = i + 1; j < td->organ_count; ++j, ++p) {
        cJSON *pair = cJSON_CreateObject();
        const char *names[2] = {r->scene->organs[td->organs[i]].name, r->scene->organs[td->organs[j]].name};
        cJSON_AddItemToObject(pair, "organs", cJSON_CreateStringArray(names, 2));
        cJSON_AddNumberToObject(pair, "volume", v->tissues[t].pair_volume[p]);
        cJSON_AddItemToArray(pairs, pair);
      }
    occupied_json(e, r->scene, v->tissues + t);
    tissue_hold hold;
    if (tissue_hold_count(r, t, &hold)) {
      cJSON_AddStringToObject(e, "form", fascia_prep_form_name(td->form));
      cJSON_AddNumberToObject(e, "frames", hold.frames);
      cJSON_AddNumberToObject(e, "free_frames", hold.free);
      cJSON_AddNumberToObject(e, "mid_layer_frames", r->points->tissue_mid_layer_frames[t]);
      cJSON_AddNumberToObject(e, "held_layer_volume", r->points->tissue_held_layer_volume[t]);
      cJSON *shared = cJSON_AddObjectToObject(e, "shared_frames"); // organ name -> frames shared with it
      cJSON *others = cJSON_AddObjectToObject(e, "touches_unconnected"); // organ -> {shared, free}
      for (int32_t o = 0; o < r->meshes->count; ++o) {
        if (hold.shared[o]) cJSON_AddNumberToObject(shared, r->meshes->organs[o].name, hold.shared[o]);
        if (fascia_prep_tissue_connects(td, o) || (!hold.shared[o] && !hold.touched_free[o])) continue;
        cJSON *other = cJSON_AddObjectToObject(others, r->meshes->organs[o].name);
        cJSON_AddNumberToObject(other, "shared_frames", hold.shared[o]);
        cJSON_AddNumberToObject(other, "free_frames", hold.touched_free[o]);
      }
      cJSON_AddBoolToObject(e, "couple_others", td->couple_others);
      if (hold.frames > 0 && hold.free == 0 && !held_layer_only(r, t)) {
        char line[768];
        no_free_frame_warning(r, t, hold.frames, line, sizeof line);
        cJSON_AddItemToArray(warnings, cJSON_CreateString(line));
      }
    }
    tissue_hold_free(&hold);
    char coarse[768];
    if (coarse_frames_warning(r, t, coarse, sizeof coarse)) cJSON_AddItemToArray(warnings, cJSON_CreateString(coarse));
    double sample_volume = 0;
    for (int32_t s = 0; s < r->points->sample_count; ++s)
      if (r->points->sample_tissue[s] == t && !r->points->sample_drilling[s]) // a stabiliser repeats others'
        sample_volume += r->points->sample_volume[s];
    const int tet = r->scene->tissues[t].shape_kind == FASCIA_PREP_SHAPE_TET;
    cJSON_AddNumberToObject(e, "sample_volume", sample_volume);
    if (td->form == FASCIA_PREP_FORM_STRAND) {
      cJSON_AddStringToObject(e, "sample_volume_of", "length x cross-section area");
      cJSON_AddNumberToObject(e, "length", sample_volume / td->area);
      cJSON_AddNumberToObject(e, "area", td->area);
      cJSON_AddNumberToObject(e, "radius", td->radius);
    } else if (td->form == FASCIA_PREP_FORM_SHEET) {
      cJSON_AddStringToObject(e, "sample_volume_of", "mesh area x thickness");
      cJSON_AddNumberToObject(e, "area", sample_volume / td->thickness);
      cJSON_AddNumberToObject(e, "thickness", td->thickness);
    } else {
      cJSON_AddStringToObject(e, "sample_volume_of", tet ? "tetrahedra kept inside the region" : "region voxels");
    }
    cJSON_AddItemToArray(tissues, e);
  }
  cJSON *organs = cJSON_AddArrayToObject(root, "organs");
  for (int32_t o = 0; o < r->meshes->count; ++o) {
    const fascia_prep_mesh *m = r->meshes->organs + o;
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "name", m->name);
    cJSON_AddNumberToObject(e, "triangles", m->triangle_count);
    cJSON_AddNumberToObject(e, "border_edges", m->report.border_edges);
    cJSON_AddNumberToObject(e, "self_intersecting_face_pairs", m->report.self_intersections);
    cJSON_AddNumberToObject(e, "enclosed_volume", m->report.enclosed_volume);
    cJSON_AddStringToObject(e, "inside_rule", m->report.inside_rule);
    cJSON_AddItemToArray(organs, e);
  }
  cJSON *overlaps = cJSON_AddArrayToObject(root, "overlaps");
  for (int32_t k = 0; k < v->overlap_count; ++k) {
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "a", r->meshes->organs[v->overlaps[k].a].name);
    cJSON_AddStringToObject(e, "b", r->meshes->organs[v->overlaps[k].b].name);
    cJSON_AddNumberToObject(e, "volume", v->overlaps[k].volume);
    cJSON_AddNumberToObject(e, "depth", v->overlaps[k].depth);
    cJSON_AddItemToArray(overlaps, e);
  }
  cJSON *contacts = cJSON_AddArrayToObject(root, "label_contacts");
  for (int32_t k = 0; k < r->meshes->contact_count; ++k) {
    const fascia_prep_label_contact *lc = r->meshes->contacts + k;
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "a", r->meshes->organs[lc->a].name);
    cJSON_AddStringToObject(e, "b", r->meshes->organs[lc->b].name);
    cJSON_AddNumberToObject(e, "faces", (double)lc->faces);
    cJSON_AddNumberToObject(e, "area", lc->area);
    cJSON_AddNumberToObject(e, "layer", lc->layer);
    cJSON_AddItemToArray(contacts, e);
  }
  cJSON *gaps = cJSON_AddArrayToObject(root, "gaps");
  static const char *const kinds[] = {"", "overlap", "contact", "thin", "gap"};
  for (int32_t a = 0; a < v->organ_count; ++a)
    for (int32_t b = a + 1; b < v->organ_count; ++b) {
      const int kind = gap_kind(r, a, b);
      if (kind == GAP_NONE) continue;
      const double d = v->closest[a * v->organ_count + b];
      cJSON *e = cJSON_CreateObject();
      cJSON_AddStringToObject(e, "a", r->meshes->organs[a].name);
      cJSON_AddStringToObject(e, "b", r->meshes->organs[b].name);
      cJSON_AddNumberToObject(e, "distance", d);
      cJSON_AddStringToObject(e, "kind", kinds[kind]);
      cJSON_AddItemToArray(gaps, e);
      if (kind == GAP_THIN) {
        char line[512];
        thin_gap_warning(r, a, b, line, sizeof line);
        cJSON_AddItemToArray(warnings, cJSON_CreateString(line));
      }
    }
  cJSON *steps = cJSON_AddArrayToObject(root, "steps");
  double total = 0;
  for (int k = 0; k < c->count; ++k) {
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "name", c->name[k]);
    cJSON_AddNumberToObject(e, "seconds", c->seconds[k]);
    cJSON_AddNumberToObject(e, "peak_bytes", c->peak_bytes[k]);
    cJSON_AddItemToArray(steps, e);
    total += c->seconds[k];
  }
  cJSON_AddNumberToObject(root, "seconds", total);
  (void)cli_json_emit(root, 0);
  cJSON_Delete(root);
}

// The model, preview and label-map files against the scene and its meshes, and the
// folders they go to, before the first stage (cli_check_paths).
static int check_prep_paths(const fascia_prep_scene *scene, const char *output, const char *preview,
                            const char *labelmap, const char *label_table) {
  // each organ's surface is <organ>.vtp
  static const char *const preview_names[] = {"preview.pvd", "region.vti", "frames.vtu", "samples.vtu", "coupling.vtu",
                                              "*.vtp", NULL};
  cli_path *paths = calloc((size_t)scene->organ_count + 7, sizeof *paths);
  char(*keys)[48] = calloc((size_t)scene->organ_count + 1, sizeof *keys); // "organs[k].mesh", as the scene says
  if (!paths || !keys) {
    free(paths), free(keys);
    fprintf(stderr, "fascia prep: out of memory\n");
    return 1;
  }
  int n = 0;
  paths[n++] = (cli_path){"scene", scene->path, CLI_INPUT, NULL, NULL};
  for (int32_t o = 0; o < scene->organ_count; ++o) { // a label organ's file is the segmentation, below
    snprintf(keys[o], sizeof keys[o], "organs[%d].mesh", (int)o);
    if (!scene->organs[o].label_count)
      paths[n++] = (cli_path){keys[o], scene->organs[o].mesh_path, CLI_INPUT, NULL, NULL};
  }
  // the segmentation and its label table (a TSV named in the scene, against its folder; not a built-in table)
  const fascia_prep_segmentation *seg = &scene->segmentation;
  char table[4096] = "", folder[4096];
  if (seg->file && seg->table && strncmp(seg->table, "totalsegmentator:", 17)) {
    if (seg->table[0] == '/') snprintf(table, sizeof table, "%s", seg->table);
    else snprintf(table, sizeof table, "%s/%s", fascia_path_folder(scene->path, folder, sizeof folder), seg->table);
  }
  paths[n++] = (cli_path){"segmentation.file", seg->file ? seg->file_path : NULL, CLI_INPUT, NULL, NULL};
  paths[n++] = (cli_path){"segmentation.labels", table[0] ? table : NULL, CLI_INPUT, NULL, NULL};
  paths[n++] = (cli_path){"-o", output, CLI_OUTPUT_FILE, NULL, NULL};
  paths[n++] = (cli_path){"--preview", preview, CLI_OUTPUT_DIR, preview_names, NULL};
  paths[n++] = (cli_path){"--labelmap", labelmap, CLI_OUTPUT_FILE, NULL, NULL};
  paths[n++] = (cli_path){"--labelmap's table", label_table, CLI_OUTPUT_FILE, NULL, NULL};
  const int rc = cli_check_paths("prep", paths, n);
  free(paths);
  free(keys);
  return rc;
}

// --estimate: what preparing will take, for a scheduler (docs/cohort.md); nothing written.
static int print_estimate(fascia_ctx *ctx, const fascia_prep_scene *scene, int json) {
  fascia_prep_estimate_report e;
  const fascia_status st = fascia_prep_estimate(ctx, scene, &e);
  if (st != FASCIA_OK) return cli_fail("prep", ctx, st);
  const double mib = e.peak_bytes / 1048576;
  fprintf(stderr, "fascia prep: %s: expected peak memory %.0f MiB (%.3g grid voxels of %g m, %.3g triangles)\n",
          scene->path, mib, e.grid_voxels, scene->voxel_size, e.triangles);
  if (!json) return 0;
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "scene", scene->path);
  cJSON_AddNumberToObject(root, "grid_voxels", e.grid_voxels);
  cJSON_AddNumberToObject(root, "organ_voxels", e.organ_voxels);
  cJSON_AddNumberToObject(root, "triangles", e.triangles);
  cJSON_AddNumberToObject(root, "input_bytes", e.input_bytes);
  cJSON_AddNumberToObject(root, "input_voxels", e.input_voxels);
  cJSON_AddNumberToObject(root, "peak_bytes", e.peak_bytes);
  cJSON_AddNumberToObject(root, "peak_mib", (double)(int64_t)(mib + 1));
  cJSON *absent = cJSON_AddArrayToObject(root, "absent_organs");
  for (int32_t k = 0; k < scene->absent_organ_count; ++k)
    cJSON_AddItemToArray(absent, cJSON_CreateString(scene->absent_organs[k]));
  const int rc = cli_json_emit(root, 0);
  cJSON_Delete(root);
  return rc;
}

int fascia_prep_command(int argc, char **argv) {
  const char *scene_path = NULL, *output = NULL, *preview = NULL, *labelmap = NULL;
  char label_table[4096] = "";
  int json = 0, threads = 0, estimate = 0;
  for (int k = 1; k < argc; ++k) {
    if (cli_help(argv[k], cli_prep_usage, NULL)) {
      return 0;
    } else if (!strcmp(argv[k], "--json")) {
      json = 1;
    } else if (!strcmp(argv[k], "--verbose")) {
    } else if (!strcmp(argv[k], "--estimate")) {
      estimate = 1;
    } else if ((!strcmp(argv[k], "-o") || !strcmp(argv[k], "--output")) && k + 1 < argc) {
      output = argv[++k];
    } else if (!strcmp(argv[k], "--preview") && k + 1 < argc) {
      preview = argv[++k];
    } else if (!strcmp(argv[k], "--labelmap") && k + 1 < argc) {
      labelmap = argv[++k];
      if (!fascia_prep_labelmap_table_path(labelmap, label_table, sizeof label_table)) {
        fprintf(stderr, "fascia prep: --labelmap '%s': the name must end in .nii or .nii.gz\n", labelmap);
        return 2;
      }
    } else if (!strcmp(argv[k], "--threads") && k + 1 < argc) {
      if (!cli_parse_threads(argv[++k], &threads)) {
        fprintf(stderr, "fascia prep: --threads expects a whole number from 1 to %d, found '%s'\n", CLI_MAX_THREADS,
                argv[k]);
        return 2;
      }
    } else if (argv[k][0] == '-') {
      fprintf(stderr, "fascia prep: unknown option '%s' (or its value is missing)\n%s", argv[k], cli_prep_usage);
      return 2;
    } else if (!scene_path) {
      scene_path = argv[k];
    } else {
      fprintf(stderr, "fascia prep: one scene file only, found '%s' after '%s'\n", argv[k], scene_path);
      return 2;
    }
  }
  if (!scene_path) {
    fprintf(stderr, "fascia prep: no scene file given\n%s", cli_prep_usage);
    return 2;
  }
  fascia_ctx *ctx = cli_ctx(threads, 1);
  prep_run r;
  memset(&r, 0, sizeof r);
  step_clock clock;
  memset(&clock, 0, sizeof clock);
  fascia_status st;
  int rc = 1;
#define STEP(name, call)                                                                                              \
  do {                                                                                                                \
    step_begin(&clock);                                                                                               \
    st = (call);                                                                                                      \
    step_end(&clock, name);                                                                                           \
    if (st != FASCIA_OK) goto fail;                                                                                   \
  } while (0)
  STEP("scene", fascia_prep_scene_load(ctx, scene_path, &r.scene));
  if (estimate) {
    rc = print_estimate(ctx, r.scene, json);
    goto done;
  }
  if (!output) output = r.scene->output;
  if (!output) {
    fprintf(stderr, "fascia prep: no output file: give -o MODEL.h5 or an \"output\" key in '%s'\n", scene_path);
    rc = 2;
    goto done;
  }
  if ((rc = check_prep_paths(r.scene, output, preview, labelmap, labelmap ? label_table : NULL)) >= 0) goto done;
  rc = 1;
  STEP("import", fascia_prep_import(ctx, r.scene, &r.meshes));
  STEP("check/repair", fascia_prep_repair(ctx, r.scene, r.meshes));
  STEP("voxelize", fascia_prep_voxelize(ctx, r.scene, r.meshes, &r.volume));
  STEP("sample", fascia_prep_sample(ctx, r.scene, r.meshes, r.volume, &r.points));
  STEP("shape functions", fascia_prep_shape_functions(ctx, r.scene, r.volume, r.points, &r.weights));
  STEP("coupling", fascia_prep_couple(ctx, r.scene, r.meshes, r.points, &r.coupling));
  {
    char command_line[2048] = "fascia";
    for (int k = 0; k < argc; ++k) {
      strncat(command_line, " ", sizeof command_line - strlen(command_line) - 1);
      strncat(command_line, argv[k], sizeof command_line - strlen(command_line) - 1);
    }
    char tool[64];
    snprintf(tool, sizeof tool, "fascia prep %s", fascia_version());
    fascia_prep_run_info info = {tool, command_line, clock.count, clock.name, clock.seconds, clock.peak_bytes};
    STEP("package", fascia_prep_package(ctx, r.scene, r.meshes, r.volume, r.points, r.weights, r.coupling, &info,
                                        &r.model));
  }
  STEP("write", fascia_model_save(ctx, r.model, output));
  if (labelmap) {
    step_begin(&clock);
    st = fascia_prep_labelmap_write(ctx, r.scene, r.meshes, labelmap, label_table, sizeof label_table);
    step_end(&clock, "label map");
    if (st != FASCIA_OK) {
      remove(output); // all or nothing, as for the preview
      goto fail;
    }
  }
  if (preview) {
    step_begin(&clock);
    st = fascia_prep_preview(ctx, preview, r.scene, r.meshes, r.volume, r.points, r.coupling);
    step_end(&clock, "preview");
    if (st != FASCIA_OK) {
      remove(output); // all or nothing: the model goes with its preview
      if (labelmap) remove(labelmap), remove(label_table);
      goto fail;
    }
  }
#undef STEP
  print_summary(&r, &clock, output, preview);
  if (labelmap) fprintf(stderr, "label map: %s, its table %s\n", labelmap, label_table);
  if (json) print_json(&r, &clock, output, preview);
  rc = 0;
  goto done;
fail:
  // the sizes that look wrong may be why it failed; the error line says so itself when it found them
  if (!strstr(fascia_ctx_message(ctx), "units look wrong")) print_warnings(r.meshes);
  rc = cli_fail("prep", ctx, st);
done:
  fascia_prep_stages_free(&r);
  fascia_ctx_destroy(&ctx);
  return rc;
}
