// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `--json`: whatever happens, a command given --json prints one JSON value
// on stdout that says how it ended, and that value is valid UTF-8.
//  - Every --json output goes through cli_json_emit, which adds the exit
//    status and the error line, and replaces bytes that are not UTF-8 (a
//    file name, an organ name read from a file) before printing.
//  - Error lines are written to stderr from many places (the commands, the
//    path checks, the libraries' messages through cli_fail): rather than
//    route each through one function, stderr is teed while --json is on, so
//    the last "fascia ...:" line is known wherever it was written.
//  - A command that ends without emitting (a usage error, a model that does
//    not load) gets {"command", "exit_status", "error"} from cli_json_finish.
#define _GNU_SOURCE // fopencookie
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "commands.h"

#define LINE_TEXT 4096

static struct {
  int on, emitted, help;
  const char *command;
  char line[LINE_TEXT];  ///< the stderr line being written
  size_t line_length;
  char error[LINE_TEXT]; ///< the last complete "fascia ..." line
} json_state;

// The tee: every byte goes to file descriptor 2 at once (progress stays
// live), and complete lines are kept.
static ssize_t tee_write(void *cookie, const char *data, size_t size) {
  (void)cookie;
  size_t done = 0;
  while (done < size) {
    const ssize_t n = write(2, data + done, size - done);
    if (n <= 0) break;
    done += (size_t)n;
  }
  for (size_t k = 0; k < size; ++k) {
    const char c = data[k];
    if (c == '\r') { // a progress line redrawn: not an error line
      json_state.line_length = 0;
    } else if (c == '\n') {
      json_state.line[json_state.line_length] = '\0';
      if (!strncmp(json_state.line, "fascia", 6)) memcpy(json_state.error, json_state.line, json_state.line_length + 1);
      json_state.line_length = 0;
    } else if (json_state.line_length + 1 < LINE_TEXT) {
      json_state.line[json_state.line_length++] = c;
    }
  }
  return (ssize_t)size; // what could not reach fd 2 is lost there as it would be with stdio
}

void cli_json_setup(const char *command, int argc, char **argv) {
  int wanted = 0;
  for (int k = 1; k < argc; ++k) {
    wanted |= !strcmp(argv[k], "--json");
    json_state.help |= !strcmp(argv[k], "--help") || !strcmp(argv[k], "-h"); // help text is the output asked for
  }
  if (!wanted) return;
  json_state.on = 1;
  json_state.command = command;
  cookie_io_functions_t io = {NULL, tee_write, NULL, NULL};
  FILE *tee = fopencookie(NULL, "w", io);
  if (!tee) return; // the error lines then go out untouched; the fallback says only the status
  setvbuf(tee, NULL, _IONBF, 0);
  stderr = tee;
}

int cli_json_on(void) { return json_state.on; }

// Length of the valid UTF-8 sequence at s (1-4), or 0 when it is not one
// (overlong forms, surrogates and code points past U+10FFFF included).
static int utf8_sequence(const unsigned char *s) {
  if (s[0] < 0x80) return 1;
  int n;
  unsigned cp;
  if (s[0] >= 0xC2 && s[0] <= 0xDF) n = 2, cp = s[0] & 0x1Fu;
  else if (s[0] >= 0xE0 && s[0] <= 0xEF) n = 3, cp = s[0] & 0x0Fu;
  else if (s[0] >= 0xF0 && s[0] <= 0xF4) n = 4, cp = s[0] & 0x07u;
  else return 0;
  for (int k = 1; k < n; ++k) {
    if ((s[k] & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (s[k] & 0x3Fu);
  }
  if ((n == 3 && cp < 0x800) || (n == 4 && (cp < 0x10000 || cp > 0x10FFFF)) || (cp >= 0xD800 && cp <= 0xDFFF))
    return 0;
  return n;
}

char *cli_utf8_copy(const char *text) {
  const unsigned char *s = (const unsigned char *)text;
  size_t length = 0;
  for (size_t k = 0; s[k];) {
    const int n = utf8_sequence(s + k);
    length += n ? (size_t)n : 3, k += n ? (size_t)n : 1;
  }
  char *out = cJSON_malloc(length + 1);
  if (!out) return NULL;
  size_t w = 0;
  for (size_t k = 0; s[k];) {
    const int n = utf8_sequence(s + k);
    if (n) {
      memcpy(out + w, s + k, (size_t)n);
      w += (size_t)n, k += (size_t)n;
    } else { // U+FFFD, the replacement character, for each byte that is not UTF-8
      memcpy(out + w, "\xEF\xBF\xBD", 3);
      w += 3, k += 1;
    }
  }
  out[w] = '\0';
  return out;
}

static int valid_utf8(const char *text) {
  for (const unsigned char *s = (const unsigned char *)text; *s;) {
    const int n = utf8_sequence(s);
    if (!n) return 0;
    s += n;
  }
  return 1;
}

// Makes every key and string in the tree valid UTF-8; 0 when out of memory.
static int make_utf8(cJSON *item) {
  for (; item; item = item->next) {
    if (item->string && !valid_utf8(item->string)) {
      char *key = cli_utf8_copy(item->string);
      if (!key) return 0;
      if (!(item->type & cJSON_StringIsConst)) cJSON_free(item->string);
      item->string = key;
      item->type &= ~cJSON_StringIsConst;
    }
    if (cJSON_IsString(item) && item->valuestring && !valid_utf8(item->valuestring)) {
      char *value = cli_utf8_copy(item->valuestring);
      if (!value) return 0;
      cJSON_free(item->valuestring);
      item->valuestring = value;
    }
    if (item->child && !make_utf8(item->child)) return 0;
  }
  return 1;
}

int cli_json_emit(cJSON *root, int exit_status) {
  if (cJSON_IsObject(root)) {
    cJSON_DeleteItemFromObject(root, "exit_status");
    cJSON_DeleteItemFromObject(root, "error");
    cJSON_AddNumberToObject(root, "exit_status", exit_status);
    if (exit_status != 0 && json_state.error[0]) cJSON_AddStringToObject(root, "error", json_state.error);
    else cJSON_AddNullToObject(root, "error");
  }
  char *text = make_utf8(root) ? cJSON_PrintUnformatted(root) : NULL;
  if (!text) {
    fprintf(stderr, "fascia %s: out of memory for the JSON output\n", json_state.command ? json_state.command : "");
    return 1;
  }
  printf("%s\n", text);
  fflush(stdout);
  cJSON_free(text);
  json_state.emitted = 1;
  return exit_status;
}

int cli_json_finish(int exit_status) {
  if (!json_state.on || json_state.emitted || json_state.help) return exit_status;
  fflush(stderr);
  cJSON *root = cJSON_CreateObject();
  if (!root) return exit_status;
  cJSON_AddStringToObject(root, "command", json_state.command ? json_state.command : "");
  cli_json_emit(root, exit_status);
  cJSON_Delete(root);
  return exit_status;
}
