// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The source of libfascia_sim.so that CMake asks for: its code is the static
// archive's, linked whole (sim/CMakeLists.txt); C needs one declaration here.
typedef int fascia_shared_library_unit;
