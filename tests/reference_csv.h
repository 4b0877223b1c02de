// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Reads the stored references of data/reference/ (plain CSV: a header row,
// no quoted fields) in tests.
#ifndef FASCIA_TESTS_REFERENCE_CSV_H
#define FASCIA_TESTS_REFERENCE_CSV_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define REFERENCE_CSV_COLUMNS 32
#define REFERENCE_CSV_LINE 1024

/// Splits line (modified) at commas into at most REFERENCE_CSV_COLUMNS fields.
static int reference_csv_split(char *line, char **field) {
  int n = 0;
  line[strcspn(line, "\r\n")] = '\0';
  for (char *p = line; n < REFERENCE_CSV_COLUMNS;) {
    field[n++] = p;
    char *comma = strchr(p, ',');
    if (!comma) break;
    *comma = '\0';
    p = comma + 1;
  }
  return n;
}

/// Column `name` of the one row of `path` whose columns key[2j] equal the
/// texts key[2j + 1] (j < pairs), into *out. 0 (and a line on stderr) if the
/// file, a column or the row is missing, or more than one row matches.
static int reference_csv_number(const char *path, const char *const *key, int pairs, const char *name,
                                double *out) {
  FILE *f = fopen(path, "r");
  if (!f) {
    fprintf(stderr, "%s: cannot open\n", path);
    return 0;
  }
  char header[REFERENCE_CSV_LINE], line[REFERENCE_CSV_LINE], *head[REFERENCE_CSV_COLUMNS], *cell[REFERENCE_CSV_COLUMNS];
  int found = 0, columns = 0, want = -1, at[16];
  if (fgets(header, sizeof header, f)) columns = reference_csv_split(header, head);
  for (int c = 0; c < columns; ++c)
    if (!strcmp(head[c], name)) want = c;
  for (int j = 0; j < pairs && j < 16; ++j) {
    at[j] = -1;
    for (int c = 0; c < columns; ++c)
      if (!strcmp(head[c], key[2 * j])) at[j] = c;
    if (at[j] < 0) want = -1;
  }
  while (want >= 0 && fgets(line, sizeof line, f)) {
    const int n = reference_csv_split(line, cell);
    int match = n == columns;
    for (int j = 0; match && j < pairs; ++j) match = !strcmp(cell[at[j]], key[2 * j + 1]);
    if (match) {
      *out = strtod(cell[want], NULL);
      ++found;
    }
  }
  fclose(f);
  if (found != 1) fprintf(stderr, "%s: %d rows with %s = %s ... and a column %s, expected one\n", path, found, key[0], key[1], name);
  return found == 1;
}

#endif
