// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Prescribed rigid motions: keyframes interpolated linearly in translation
// and spherically (slerp) in rotation, held at the last key afterwards and at
// the first key before it.
#include "point/linalg.h"
#include "solve/motion.h"

static void slerp(const fascia_real *a, const fascia_real *b, fascia_real s, fascia_real *out) {
  fascia_real c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3], sign = 1;
  if (c < 0) { // the shorter arc
    c = -c;
    sign = -1;
  }
  fascia_real wa = 1 - s, wb = s;
  if (c < FASCIA_R(0.9999)) {
    const fascia_real angle = acos(c), sn = sin(angle);
    wa = sin((1 - s) * angle) / sn;
    wb = sin(s * angle) / sn;
  }
  for (int k = 0; k < 4; ++k) out[k] = wa * a[k] + sign * wb * b[k];
  fascia_pt_quat_normalize(out);
}

void fascia_motion_pose(const fascia_motion *mo, fascia_real t, fascia_real *translation, fascia_real *rotation) {
  int32_t k = 0;
  if (t <= mo->key_time[0] || mo->key_count == 1) k = -1;
  else if (t >= mo->key_time[mo->key_count - 1]) k = mo->key_count - 1;
  else
    while (k + 1 < mo->key_count && mo->key_time[k + 1] <= t) ++k;
  if (k < 0 || k == mo->key_count - 1) {
    const int32_t j = k < 0 ? 0 : k;
    for (int c = 0; c < 3; ++c) translation[c] = mo->key_translation[3 * j + c];
    for (int c = 0; c < 4; ++c) rotation[c] = mo->key_rotation[4 * j + c];
    return;
  }
  const fascia_real s = (t - mo->key_time[k]) / (mo->key_time[k + 1] - mo->key_time[k]);
  for (int c = 0; c < 3; ++c)
    translation[c] = (1 - s) * mo->key_translation[3 * k + c] + s * mo->key_translation[3 * (k + 1) + c];
  slerp(mo->key_rotation + 4 * k, mo->key_rotation + 4 * (k + 1), s, rotation);
}

void fascia_motion_frame(const fascia_model *m, int32_t i, fascia_real t, fascia_real *x, fascia_real *q) {
  const fascia_motion *mo = m->motions + m->frame_motion[i];
  fascia_real T[3], Q[4], R[9], rel[3], moved[3];
  fascia_motion_pose(mo, t, T, Q);
  fascia_pt_quat_to_mat(Q, R);
  for (int c = 0; c < 3; ++c) rel[c] = m->frame_position[3 * i + c] - mo->pivot[c];
  fascia_pt_mat_vec(R, rel, moved);
  for (int c = 0; c < 3; ++c) x[c] = mo->pivot[c] + T[c] + moved[c];
  fascia_pt_quat_mul(Q, m->frame_rotation + 4 * i, q);
  fascia_pt_quat_normalize(q);
}

fascia_real fascia_model_motion_end(const fascia_model *m) {
  fascia_real end = 0;
  for (int32_t k = 0; m && k < m->motion_count; ++k) {
    const fascia_motion *mo = m->motions + k;
    if (mo->key_count > 0 && mo->key_time[mo->key_count - 1] > end) end = mo->key_time[mo->key_count - 1];
  }
  return end;
}
