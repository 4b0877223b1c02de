// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Umbrella header of the simulator core.
#ifndef FASCIA_FASCIA_H
#define FASCIA_FASCIA_H

#include "fascia/base.h"
#include "fascia/model.h"
#include "fascia/shape.h"
#include "fascia/results.h"
#include "fascia/solver.h"
#include "fascia/organs.h"
#include "fascia/checkpoint.h"
#include "fascia/files.h"

#endif
