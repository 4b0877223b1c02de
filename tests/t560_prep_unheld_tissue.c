// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Tissue that nothing holds: boxes A (fixed) and B (rigid) with tissue 'web'
// between them, boxes C and D (both rigid) with tissue 'loose' between them,
// far from A and B. 'loose' and the two bodies it joins would fall for ever:
// prep refuses the scene naming the tissue and its volume. Without 'loose'
// the model is built, holds no unheld piece and reports none dropped.
// Last, one tissue in two pieces: 'web' connecting all four boxes has an
// A-B piece (held by the fixed A) and a C-D piece between two rigid boxes
// that nothing holds: that piece is dropped, listed, and the model left is
// whole and held. Its region splits into the volume each pair of boxes
// bridges: half A-B, half C-D.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include "check.h"
#include "prep_fixture.h"

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "   {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"rigid\"},\n"
    "   {\"name\": \"C\", \"mesh\": \"c.obj\", \"model\": \"rigid\"},\n"
    "   {\"name\": \"D\", \"mesh\": \"d.obj\", \"model\": \"rigid\"}],\n"
    " \"tissues\": [{\"name\": \"web\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.005, \"material\": \"soft\",\n"
    "   \"frame_spacing\": 0.002, \"sample_spacing\": 0.0015}%s]}\n";
static const char loose[] = ",\n  {\"name\": \"loose\", \"connects\": [\"C\", \"D\"], \"max_gap\": 0.005, "
                            "\"material\": \"soft\", \"frame_spacing\": 0.002, \"sample_spacing\": 0.0015}";

int main(void) {
  char dir[256], path[512], text[2048];
  if (!fixture_tmpdir(dir)) return 1;
  const double lo[4][3] = {{-0.03, -0.01, -0.01}, {0.002, -0.01, -0.01}, {-0.03, -0.01, 0.06}, {0.002, -0.01, 0.06}};
  const double hi[4][3] = {{-0.002, 0.01, 0.01}, {0.03, 0.01, 0.01}, {-0.002, 0.01, 0.08}, {0.03, 0.01, 0.08}};
  const char *names[] = {"a.obj", "b.obj", "c.obj", "d.obj", "scene.json", NULL};
  for (int k = 0; k < 4; ++k) CHECK(fixture_box(dir, names[k], lo[k], hi[k]));
  snprintf(path, sizeof path, "%s/scene.json", dir);

  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  snprintf(text, sizeof text, scene_format, loose);
  CHECK(fixture_write(dir, "scene.json", text));
  const fascia_status st = fixture_prep(ctx, path, &r);
  const char *msg = fascia_ctx_message(ctx);
  fprintf(stderr, "with 'loose': %s: %s\n", fascia_status_name(st), msg);
  CHECK(st == FASCIA_ERR_ARGUMENT);
  CHECK(r.model == NULL);
  CHECK(strstr(msg, "tissue 'loose'") && strstr(msg, "cm^3") && strstr(msg, "nothing holds it") &&
        strstr(msg, "scene.json"));
  fixture_free(&r);

  snprintf(text, sizeof text, scene_format, "");
  CHECK(fixture_write(dir, "scene.json", text));
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  int32_t count = -1;
  CHECK_OK(fascia_model_floating_components(ctx, r.model, NULL, NULL, 0, &count), ctx);
  CHECK(count == 0);
  CHECK(r.model->provenance && strstr(r.model->provenance, "\"unheld_pieces_dropped\":[]"));
  fixture_free(&r);

  // one tissue, two pieces, one of them held by nothing: 'web' connects all
  // four boxes; its A-B piece is held by A, its C-D piece (two rigid boxes,
  // far from A and B) by nothing
  static const char two_pieces[] =
      "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
      " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
      " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
      "   {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"rigid\"},\n"
      "   {\"name\": \"C\", \"mesh\": \"c.obj\", \"model\": \"rigid\"},\n"
      "   {\"name\": \"D\", \"mesh\": \"d.obj\", \"model\": \"rigid\"}],\n"
      " \"tissues\": [{\"name\": \"web\", \"connects\": [\"A\", \"B\", \"C\", \"D\"], \"max_gap\": 0.005, "
      "\"material\": \"soft\", \"frame_spacing\": 0.002, \"sample_spacing\": 0.0015}]}\n";
  CHECK(fixture_write(dir, "scene.json", two_pieces));
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  // the region's volume by the pair each voxel bridges: A-B and C-D, the same slab each; no other pair
  const fascia_prep_tissue_report *web = r.volume ? r.volume->tissues : NULL;
  if (web) {
    const double *pair = web->pair_volume; // (A,B) (A,C) (A,D) (B,C) (B,D) (C,D)
    CHECK_NEAR(pair[0] + pair[1] + pair[2] + pair[3] + pair[4] + pair[5], web->volume, 1e-12, 0);
    CHECK_NEAR(pair[0], 0.5 * web->volume, 1e-9, 0);
    CHECK(pair[1] == 0 && pair[2] == 0 && pair[3] == 0 && pair[4] == 0);
  }
  CHECK_OK(fascia_model_floating_components(ctx, r.model, NULL, NULL, 0, &count), ctx);
  CHECK(count == 0);
  const char *list = r.model->provenance ? strstr(r.model->provenance, "\"unheld_pieces_dropped\":[{") : NULL;
  CHECK(list && strstr(list, "\"tissue\":\"web\"") && strstr(list, "\"frames\":"));
  fprintf(stderr, "two pieces: %d of %d frames and %d of %d samples kept\n", (int)r.model->frame_count,
          (int)r.points->frame_count, (int)r.model->sample_count, (int)r.points->sample_count);
  CHECK(r.model->frame_count < r.points->frame_count && r.model->sample_count < r.points->sample_count);
  // the held piece keeps its coupling to A and B; the dropped one loses its own
  CHECK(r.model->frame_count > 0 && r.model->coupling_count > 0 && r.model->coupling_count < r.coupling->count);
  fixture_free(&r);

  fascia_ctx_destroy(&ctx);
  fixture_cleanup(dir, names);
  return check_failures_ != 0;
}
