// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Prescribed rigid motions of the model (motion.c): what the solver and the
// organs read of them.
#ifndef FASCIA_SRC_MOTION_H
#define FASCIA_SRC_MOTION_H
#include "fascia/model.h"
#include "util/status.h"

/// Pose of a prescribed motion at time t: translation [3], rotation [4].
FASCIA_INTERN void fascia_motion_pose(const fascia_motion *motion, fascia_real t, fascia_real *translation,
                                      fascia_real *rotation);
/// Position and rotation of frame i following its motion at time t.
FASCIA_INTERN void fascia_motion_frame(const fascia_model *model, int32_t i, fascia_real t, fascia_real *x,
                                       fascia_real *q);
#endif
