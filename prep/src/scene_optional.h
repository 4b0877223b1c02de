// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Optional organs of a scene (an organ's "optional": true): one template
// scene serves a cohort whose segmentations lack some organs.
#ifndef FASCIA_PREP_SCENE_OPTIONAL_H
#define FASCIA_PREP_SCENE_OPTIONAL_H

#include <cjson/cJSON.h>

#include "prep_util.h"

/// Reads the scene's label map and removes from root (the scene's JSON) every
/// optional organ none of whose labels the map holds, its name from each
/// tissue's "connects" and "coupling", and each tissue left without the
/// organs its form needs (a volume two, a sheet one, a strand both ends; a
/// region on the organ's parts). The names removed go to scene's
/// absent_organs and dropped_tissues; *edited is 1 when root changed (the
/// caller parses it again). Errors: the label map unreadable, or no tissue
/// left; root is then unchanged or partly edited, to be discarded.
FASCIA_PREP_INTERN fascia_status prep_scene_leave_out_absent(fascia_ctx *ctx, fascia_prep_scene *scene, cJSON *root,
                                                            int *edited);

#endif
