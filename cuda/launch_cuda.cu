// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The launcher on NVIDIA GPUs, through the CUDA runtime API (launch.h). An
// item of items.h is one thread. Each kernel id and each reduction's terms id
// gets its own __global__ (a template on the id), so that the switches of
// fascia_dev_item and fascia_dev_term fold at compile time and each kernel
// pays registers for its own body only.
//
// All work goes into one stream, so launches are ordered without further
// synchronization. A reduction is one launch: every block stores its partial
// sums and the last block to finish adds them in a fixed order and runs the
// scalar step. Its grid depends on the item count only, so sums are the same
// bits on every run (they differ in rounding from the emulation's item-order
// sums). Recorded sequences are CUDA graphs captured from that stream.
#include <cuda_runtime.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#include "launch.h"
extern "C" {
#include "fascia/base.h"
}

/// Threads of a reduction block: a power of two for the tree sum.
#define REDUCE_THREADS 256
/// Most blocks of a reduction: enough to fill an H100 several times over,
/// and few enough that the last block adds the partials in one short pass.
#define REDUCE_MAX_BLOCKS 1024

struct fascia_launcher {
  fascia_ctx *ctx;
  int device;
  cudaStream_t stream;           // all work, in order
  fascia_real *d_partials;       // [REDUCE_MAX_BLOCKS * 4] block sums of the running reduction
  unsigned int *d_blocks_done;   // blocks of the running reduction that stored their sums
  cudaGraphExec_t sequences[FASCIA_LAUNCH_SLOTS]; // NULL: nothing recorded
  int recording;                 // 1 while a sequence is being captured
  cudaError_t error;             // first failed launch; cudaSuccess if none
  char error_where[96];          // which launch, e.g. "kernel 4"
  char name[384];                // prop.name is up to 256 bytes
};

// ---------------------------------------------------------------- kernels --

// The per-sample kernels (and the pair diagonal, six sample products per
// item) are heavy in registers and work: smaller blocks spread a modest
// sample count over more multiprocessors.
static constexpr __host__ __device__ int item_threads(int kernel) {
  return kernel == FASCIA_K_SAMPLE_GRADIENT || kernel == FASCIA_K_SAMPLE_STIFFNESS ||
                 kernel == FASCIA_K_SAMPLE_STIFFNESS_SMOOTHING || kernel == FASCIA_K_SAMPLE_STIFFNESS_PAPER ||
                 kernel == FASCIA_K_PAIR_DIAGONAL || kernel == FASCIA_K_CG_SAMPLE_MASS ||
                 kernel == FASCIA_K_SAMPLE_MASS || kernel == FASCIA_K_PATCH_EVALUATE ||
                 kernel == FASCIA_K_MODES_EVALUATE || kernel == FASCIA_K_MODES_TANGENT
             ? 128
             : 256;
}

// __grid_constant__ lets the items take D's address without a copy of it
// in local memory.
template <int K>
static __global__ void __launch_bounds__(item_threads(K))
    k_item(const __grid_constant__ fascia_dev D, int64_t n, const fascia_real *in, fascia_real *out,
           fascia_real value) {
  const int64_t i = blockIdx.x * (int64_t)blockDim.x + threadIdx.x;
  if (i < n) fascia_dev_item(&D, K, i, in, out, value);
}

// Sums each thread's four values over the block in a fixed tree; the totals
// end in block_sums[k][0]. Starts and ends with all threads in step.
static __device__ __forceinline__ void sum_over_block(fascia_real (*block_sums)[REDUCE_THREADS],
                                                      const fascia_real *sum) {
  const int tid = threadIdx.x;
  for (int k = 0; k < 4; ++k) block_sums[k][tid] = sum[k];
  __syncthreads();
  for (int half = REDUCE_THREADS / 2; half > 0; half /= 2) {
    if (tid < half)
      for (int k = 0; k < 4; ++k) block_sums[k][tid] += block_sums[k][tid + half];
    __syncthreads();
  }
}

// The last-block pattern (threadfence reduction): no second launch, so CG's
// scalar steps run on the device without a round trip through the host.
// The counter returns to zero at the end, so a graph can replay it.
template <int T>
static __global__ void __launch_bounds__(REDUCE_THREADS)
    k_reduce(const __grid_constant__ fascia_dev D, int64_t n, const fascia_real *a, const fascia_real *b, int step,
             fascia_real *d_partials, unsigned int *d_blocks_done) {
  __shared__ fascia_real block_sums[4][REDUCE_THREADS];
  __shared__ int last_block;
  const int tid = threadIdx.x;
  fascia_real sum[4] = {0, 0, 0, 0};
  const int64_t stride = (int64_t)gridDim.x * REDUCE_THREADS;
  for (int64_t i = blockIdx.x * (int64_t)REDUCE_THREADS + tid; i < n; i += stride) {
    fascia_real t[4] = {0, 0, 0, 0}; // fascia_dev_term may leave some untouched
    fascia_dev_term(&D, T, i, a, b, t);
    for (int k = 0; k < 4; ++k) sum[k] += t[k];
  }
  sum_over_block(block_sums, sum);
  if (tid == 0) {
    for (int k = 0; k < 4; ++k) d_partials[4 * blockIdx.x + k] = block_sums[k][0];
    __threadfence(); // the partials are visible before the count says so
    last_block = atomicAdd(d_blocks_done, 1u) == gridDim.x - 1;
  }
  __syncthreads(); // also: thread 0 has read block_sums before they are reused
  if (!last_block) return;
  __threadfence(); // see the other blocks' partials
  for (int k = 0; k < 4; ++k) sum[k] = 0;
  for (unsigned int block = tid; block < gridDim.x; block += REDUCE_THREADS)
    for (int k = 0; k < 4; ++k) sum[k] += __ldcg(d_partials + 4 * block + k); // L2, never a stale L1 line
  sum_over_block(block_sums, sum);
  if (tid == 0) {
    const fascia_real total[4] = {block_sums[0][0], block_sums[1][0], block_sums[2][0], block_sums[3][0]};
    fascia_dev_scalar_step(&D, step, total);
    *d_blocks_done = 0;
  }
}

// ----------------------------------------------------------------- errors --

// Keeps the first failure: later ones are mostly its consequences.
static void remember_error(fascia_launcher *L, cudaError_t error, const char *where_format, ...)
    __attribute__((format(printf, 3, 4)));

static void remember_error(fascia_launcher *L, cudaError_t error, const char *where_format, ...) {
  if (error == cudaSuccess || L->error != cudaSuccess) return;
  L->error = error;
  va_list args;
  va_start(args, where_format);
  vsnprintf(L->error_where, sizeof L->error_where, where_format, args);
  va_end(args);
}

static fascia_status report_remembered(fascia_launcher *L) {
  return FASCIA_FAIL(L->ctx, FASCIA_ERR_DEVICE, "cuda: %s in %s", cudaGetErrorString(L->error), L->error_where);
}

// A failed runtime call also leaves its error as the "last error"; clear it
// once handled, or the next launch's check would take it for its own.
static cudaError_t handled(cudaError_t error) {
  if (error != cudaSuccess) cudaGetLastError();
  return error;
}

// Errors of a kernel that ran show up at the next wait, with no kernel named.
static fascia_status report_wait(fascia_launcher *L, cudaError_t error, const char *while_doing) {
  return FASCIA_FAIL(L->ctx, FASCIA_ERR_DEVICE,
                     "cuda: %s while %s (compute-sanitizer names the kernel that failed)",
                     cudaGetErrorString(error), while_doing);
}

// ------------------------------------------------------------- lifecycle --

static void cuda_destroy(fascia_launcher *L) {
  if (!L) return;
  if (L->stream) cudaStreamSynchronize(L->stream);
  for (int s = 0; s < FASCIA_LAUNCH_SLOTS; ++s)
    if (L->sequences[s]) cudaGraphExecDestroy(L->sequences[s]);
  if (L->d_partials) cudaFree(L->d_partials);
  if (L->d_blocks_done) cudaFree(L->d_blocks_done);
  if (L->stream) cudaStreamDestroy(L->stream);
  cudaGetLastError();
  free(L);
}

// Picks the device (FASCIA_CUDA_DEVICE or 0), checks it and makes the
// stream and the reduction buffers; destroy cleans up after a failure.
static fascia_status open_device(fascia_launcher *L) {
  int count = 0;
  cudaError_t error = handled(cudaGetDeviceCount(&count));
  // without any NVIDIA driver the runtime also answers "insufficient driver"
  if (error == cudaErrorInsufficientDriver)
    return FASCIA_FAIL(L->ctx, FASCIA_ERR_UNSUPPORTED,
                       "no CUDA device: no NVIDIA driver, or one older than this build's CUDA runtime %d.%d needs",
                       CUDART_VERSION / 1000, CUDART_VERSION % 1000 / 10);
  if (error != cudaSuccess)
    return FASCIA_FAIL(L->ctx, FASCIA_ERR_UNSUPPORTED, "no CUDA device: %s", cudaGetErrorString(error));
  if (count <= 0) return FASCIA_FAIL(L->ctx, FASCIA_ERR_UNSUPPORTED, "no CUDA device: the driver reports none");
  const char *chosen = getenv("FASCIA_CUDA_DEVICE");
  if (chosen && *chosen) {
    char *end = NULL;
    const long index = strtol(chosen, &end, 10);
    FASCIA_CHECK(*end == '\0' && index >= 0 && index < count, L->ctx, FASCIA_ERR_ARGUMENT,
                 "cuda: FASCIA_CUDA_DEVICE='%s' names no device; expected an index from 0 to %d", chosen, count - 1);
    L->device = (int)index;
  }
  cudaDeviceProp prop;
  error = handled(cudaSetDevice(L->device));
  if (error == cudaSuccess) error = handled(cudaGetDeviceProperties(&prop, L->device));
  if (error != cudaSuccess)
    return FASCIA_FAIL(L->ctx, FASCIA_ERR_UNSUPPORTED, "no CUDA device: device %d: %s", L->device,
                       cudaGetErrorString(error));
  // the kernels take D as __grid_constant__, which needs Volta or newer
  FASCIA_CHECK(prop.major >= 7, L->ctx, FASCIA_ERR_UNSUPPORTED,
               "cuda: %s is sm_%d%d; fascia needs compute capability 7.0 (Volta) or newer", prop.name, prop.major,
               prop.minor);
  int runtime = 0, driver = 0;
  cudaRuntimeGetVersion(&runtime);
  cudaDriverGetVersion(&driver);
  snprintf(L->name, sizeof L->name, "%s (sm_%d%d, %zu GiB, CUDA runtime %d.%d, driver %d.%d)", prop.name, prop.major,
           prop.minor, (size_t)(prop.totalGlobalMem >> 30), runtime / 1000, runtime % 1000 / 10, driver / 1000,
           driver % 1000 / 10);

  error = handled(cudaStreamCreateWithFlags(&L->stream, cudaStreamNonBlocking));
  if (error == cudaSuccess)
    error = handled(cudaMalloc((void **)&L->d_partials, REDUCE_MAX_BLOCKS * 4 * sizeof(fascia_real)));
  if (error == cudaSuccess) error = handled(cudaMalloc((void **)&L->d_blocks_done, sizeof(unsigned int)));
  if (error == cudaSuccess) error = handled(cudaMemsetAsync(L->d_blocks_done, 0, sizeof(unsigned int), L->stream));
  if (error == cudaSuccess) error = handled(cudaStreamSynchronize(L->stream));
  if (error != cudaSuccess)
    return FASCIA_FAIL(L->ctx, FASCIA_ERR_DEVICE, "cuda: %s while setting up %s", cudaGetErrorString(error), L->name);
  return FASCIA_OK;
}

static fascia_status cuda_create(fascia_ctx *ctx, int threads, fascia_launcher **out) {
  (void)threads;
  *out = NULL;
  fascia_launcher *L = (fascia_launcher *)calloc(1, sizeof *L);
  FASCIA_CHECK(L, ctx, FASCIA_ERR_MEMORY, "cuda: out of host memory");
  L->ctx = ctx;
  const fascia_status status = open_device(L);
  if (status != FASCIA_OK) {
    cuda_destroy(L);
    return status;
  }
  *out = L;
  return FASCIA_OK;
}

static const char *cuda_name(const fascia_launcher *L) { return L->name; }

// --------------------------------------------------------------- memory --

// Allocation and transfers wait on the stream, which a capture forbids.
#define REFUSE_WHILE_RECORDING(L, what)                                                                               \
  FASCIA_CHECK(!(L)->recording, (L)->ctx, FASCIA_ERR_INTERNAL, "cuda: %s while recording a launch sequence", what)

static fascia_status cuda_alloc(fascia_launcher *L, size_t bytes, void **out) {
  *out = NULL;
  REFUSE_WHILE_RECORDING(L, "allocation");
  const size_t megabyte = (size_t)1 << 20, size = bytes ? bytes : 1; // a valid pointer even for nothing
  void *p = NULL;
  cudaError_t error = handled(cudaMalloc(&p, size));
  if (error == cudaErrorMemoryAllocation) {
    size_t free_bytes = 0, total_bytes = 0;
    handled(cudaMemGetInfo(&free_bytes, &total_bytes));
    return FASCIA_FAIL(L->ctx, FASCIA_ERR_MEMORY, "cuda: out of device memory for %zu MB (%zu MB free of %zu MB)",
                       (bytes + megabyte - 1) / megabyte, free_bytes / megabyte, total_bytes / megabyte);
  }
  if (error == cudaSuccess) error = handled(cudaMemsetAsync(p, 0, size, L->stream));
  if (error != cudaSuccess) {
    if (p) cudaFree(p);
    return FASCIA_FAIL(L->ctx, FASCIA_ERR_DEVICE, "cuda: %s while allocating %zu bytes", cudaGetErrorString(error),
                       bytes);
  }
  *out = p;
  return FASCIA_OK;
}

// Waits for the stream first: launches in flight may still use p.
static void cuda_release(fascia_launcher *L, void *p) {
  if (!p) return;
  remember_error(L, handled(cudaStreamSynchronize(L->stream)), "the launches before a release");
  remember_error(L, handled(cudaFree(p)), "release");
}

// Waits for the copy, so the caller may reuse host_src at once.
static fascia_status cuda_upload(fascia_launcher *L, void *device_dst, const void *host_src, size_t bytes) {
  REFUSE_WHILE_RECORDING(L, "upload");
  if (!bytes) return FASCIA_OK;
  cudaError_t error = handled(cudaMemcpyAsync(device_dst, host_src, bytes, cudaMemcpyHostToDevice, L->stream));
  if (error == cudaSuccess) error = handled(cudaStreamSynchronize(L->stream));
  if (error != cudaSuccess) return report_wait(L, error, "uploading");
  return FASCIA_OK;
}

static fascia_status cuda_download(fascia_launcher *L, void *host_dst, const void *device_src, size_t bytes) {
  REFUSE_WHILE_RECORDING(L, "download");
  cudaError_t error = cudaSuccess;
  if (bytes) error = handled(cudaMemcpyAsync(host_dst, device_src, bytes, cudaMemcpyDeviceToHost, L->stream));
  if (error == cudaSuccess) error = handled(cudaStreamSynchronize(L->stream));
  if (L->error != cudaSuccess) return report_remembered(L); // the cause, before its consequences
  if (error != cudaSuccess) return report_wait(L, error, "downloading");
  return FASCIA_OK;
}

static void cuda_copy(fascia_launcher *L, void *device_dst, const void *device_src, size_t bytes) {
  if (!bytes) return;
  remember_error(L, handled(cudaMemcpyAsync(device_dst, device_src, bytes, cudaMemcpyDeviceToDevice, L->stream)),
                 "copy of %zu bytes", bytes);
}

// Registering fails where a page is already locked (two small arrays on one
// page): that array then copies through the runtime's staging buffer.
static int cuda_pin(fascia_launcher *L, void *host, size_t bytes) {
  if (!host || !bytes || L->recording) return 0;
  return handled(cudaHostRegister(host, bytes, cudaHostRegisterDefault)) == cudaSuccess;
}

static void cuda_unpin(fascia_launcher *L, void *host) {
  if (!host) return;
  remember_error(L, handled(cudaStreamSynchronize(L->stream)), "the launches before an unpin");
  handled(cudaHostUnregister(host));
}

// One copy between host and device on the launcher's stream (what: "upload"
// or "download", for the message); not while recording a launch sequence.
static void cuda_copy(fascia_launcher *L, void *dst, const void *src, size_t bytes, cudaMemcpyKind kind,
                      const char *what) {
  if (!bytes) return;
  if (L->recording) {
    remember_error(L, cudaErrorStreamCaptureUnsupported, "%s while recording a launch sequence", what);
    return;
  }
  remember_error(L, handled(cudaMemcpyAsync(dst, src, bytes, kind, L->stream)), "%s of %zu bytes", what, bytes);
}

static void cuda_send(fascia_launcher *L, void *device_dst, const void *host_src, size_t bytes) {
  cuda_copy(L, device_dst, host_src, bytes, cudaMemcpyHostToDevice, "upload");
}

static void cuda_receive(fascia_launcher *L, void *host_dst, const void *device_src, size_t bytes) {
  cuda_copy(L, host_dst, device_src, bytes, cudaMemcpyDeviceToHost, "download");
}

// --------------------------------------------------------------- launches --

template <int K>
static void launch_items(fascia_launcher *L, const fascia_dev *D, int64_t n, const fascia_real *in, fascia_real *out,
                         fascia_real value) {
  const int threads = item_threads(K);
  const int64_t blocks = (n + threads - 1) / threads;
  if (blocks > INT_MAX) { // the grid's x extent is 2^31 - 1 blocks
    remember_error(L, cudaErrorInvalidConfiguration, "kernel %d (%lld items)", K, (long long)n);
    return;
  }
  k_item<K><<<(unsigned int)blocks, threads, 0, L->stream>>>(*D, n, in, out, value);
  remember_error(L, cudaGetLastError(), "kernel %d", K);
}

static void cuda_kernel(fascia_launcher *L, const fascia_dev *D, fascia_dev_kernel kernel, int64_t n,
                        const fascia_real *in, fascia_real *out, fascia_real value) {
  if (n <= 0) return;
  switch (kernel) {
  case FASCIA_K_TRIAL: launch_items<FASCIA_K_TRIAL>(L, D, n, in, out, value); break;
  case FASCIA_K_STATE: launch_items<FASCIA_K_STATE>(L, D, n, in, out, value); break;
  case FASCIA_K_MASS_SNAPSHOT: launch_items<FASCIA_K_MASS_SNAPSHOT>(L, D, n, in, out, value); break;
  case FASCIA_K_LUMPED_MASS: launch_items<FASCIA_K_LUMPED_MASS>(L, D, n, in, out, value); break;
  case FASCIA_K_SAMPLE_GRADIENT: launch_items<FASCIA_K_SAMPLE_GRADIENT>(L, D, n, in, out, value); break;
  case FASCIA_K_SAMPLE_MASS: launch_items<FASCIA_K_SAMPLE_MASS>(L, D, n, in, out, value); break;
  case FASCIA_K_FRAME_GRADIENT: launch_items<FASCIA_K_FRAME_GRADIENT>(L, D, n, in, out, value); break;
  case FASCIA_K_FRAME_MASS_APPLY: launch_items<FASCIA_K_FRAME_MASS_APPLY>(L, D, n, in, out, value); break;
  case FASCIA_K_SAMPLE_STIFFNESS: launch_items<FASCIA_K_SAMPLE_STIFFNESS>(L, D, n, in, out, value); break;
  case FASCIA_K_SAMPLE_STIFFNESS_SMOOTHING:
    launch_items<FASCIA_K_SAMPLE_STIFFNESS_SMOOTHING>(L, D, n, in, out, value);
    break;
  case FASCIA_K_SAMPLE_STIFFNESS_PAPER: launch_items<FASCIA_K_SAMPLE_STIFFNESS_PAPER>(L, D, n, in, out, value); break;
  case FASCIA_K_CG_SAMPLE_MASS: launch_items<FASCIA_K_CG_SAMPLE_MASS>(L, D, n, in, out, value); break;
  case FASCIA_K_PAIR_DIAGONAL: launch_items<FASCIA_K_PAIR_DIAGONAL>(L, D, n, in, out, value); break;
  case FASCIA_K_FRAME_PRECOND: launch_items<FASCIA_K_FRAME_PRECOND>(L, D, n, in, out, value); break;
  case FASCIA_K_DAMPING: launch_items<FASCIA_K_DAMPING>(L, D, n, in, out, value); break;
  case FASCIA_K_DAMPING_WEIGHT: launch_items<FASCIA_K_DAMPING_WEIGHT>(L, D, n, in, out, value); break;
  case FASCIA_K_PRECOND_DESCENT: launch_items<FASCIA_K_PRECOND_DESCENT>(L, D, n, in, out, value); break;
  case FASCIA_K_COPY_GRADIENT: launch_items<FASCIA_K_COPY_GRADIENT>(L, D, n, in, out, value); break;
  case FASCIA_K_STEP_ROTATION: launch_items<FASCIA_K_STEP_ROTATION>(L, D, n, in, out, value); break;
  case FASCIA_K_ACCEPT_STATIC: launch_items<FASCIA_K_ACCEPT_STATIC>(L, D, n, in, out, value); break;
  case FASCIA_K_ACCEPT_DYNAMIC: launch_items<FASCIA_K_ACCEPT_DYNAMIC>(L, D, n, in, out, value); break;
  case FASCIA_K_PATCH_EVALUATE: launch_items<FASCIA_K_PATCH_EVALUATE>(L, D, n, in, out, value); break;
  case FASCIA_K_PATCH_RATE: launch_items<FASCIA_K_PATCH_RATE>(L, D, n, in, out, value); break;
  case FASCIA_K_MODES_EVALUATE: launch_items<FASCIA_K_MODES_EVALUATE>(L, D, n, in, out, value); break;
  case FASCIA_K_MODES_TANGENT: launch_items<FASCIA_K_MODES_TANGENT>(L, D, n, in, out, value); break;
  case FASCIA_K_MODES_REDUCE: launch_items<FASCIA_K_MODES_REDUCE>(L, D, n, in, out, value); break;
  case FASCIA_K_SAVE: launch_items<FASCIA_K_SAVE>(L, D, n, in, out, value); break;
  case FASCIA_K_RESTORE: launch_items<FASCIA_K_RESTORE>(L, D, n, in, out, value); break;
  case FASCIA_K_SAMPLE_OUTPUT: launch_items<FASCIA_K_SAMPLE_OUTPUT>(L, D, n, in, out, value); break;
  case FASCIA_K_BODY_EXPAND: launch_items<FASCIA_K_BODY_EXPAND>(L, D, n, in, out, value); break;
  case FASCIA_K_BODY_GRADIENT: launch_items<FASCIA_K_BODY_GRADIENT>(L, D, n, in, out, value); break;
  case FASCIA_K_BODY_PROLONG: launch_items<FASCIA_K_BODY_PROLONG>(L, D, n, in, out, value); break;
  case FASCIA_K_FRAME_OPERATOR: launch_items<FASCIA_K_FRAME_OPERATOR>(L, D, n, in, out, value); break;
  case FASCIA_K_BODY_OPERATOR: launch_items<FASCIA_K_BODY_OPERATOR>(L, D, n, in, out, value); break;
  case FASCIA_K_BODY_DIAGONAL: launch_items<FASCIA_K_BODY_DIAGONAL>(L, D, n, in, out, value); break;
  default: remember_error(L, cudaErrorInvalidValue, "kernel %d (no such kernel)", (int)kernel); break;
  }
}

template <int T>
static void launch_reduce(fascia_launcher *L, const fascia_dev *D, int64_t n, const fascia_real *a,
                          const fascia_real *b, int step) {
  // a function of n only, so the summation order is too; one block even
  // for no items, to run the step on zero sums
  int64_t blocks = n > 0 ? (n + REDUCE_THREADS - 1) / REDUCE_THREADS : 1;
  if (blocks > REDUCE_MAX_BLOCKS) blocks = REDUCE_MAX_BLOCKS;
  k_reduce<T><<<(unsigned int)blocks, REDUCE_THREADS, 0, L->stream>>>(*D, n, a, b, step, L->d_partials,
                                                                      L->d_blocks_done);
  remember_error(L, cudaGetLastError(), "reduction %d (step %d)", T, step);
}

static void cuda_reduce(fascia_launcher *L, const fascia_dev *D, fascia_dev_terms terms, int64_t n,
                        const fascia_real *a, const fascia_real *b, fascia_dev_step step) {
  switch (terms) {
  case FASCIA_T_SAMPLES: launch_reduce<FASCIA_T_SAMPLES>(L, D, n, a, b, step); break;
  case FASCIA_T_FRAMES: launch_reduce<FASCIA_T_FRAMES>(L, D, n, a, b, step); break;
  case FASCIA_T_DOT: launch_reduce<FASCIA_T_DOT>(L, D, n, a, b, step); break;
  case FASCIA_T_SUM: launch_reduce<FASCIA_T_SUM>(L, D, n, a, b, step); break;
  case FASCIA_T_CG_START: launch_reduce<FASCIA_T_CG_START>(L, D, n, a, b, step); break;
  case FASCIA_T_OPERATOR: launch_reduce<FASCIA_T_OPERATOR>(L, D, n, a, b, step); break;
  case FASCIA_T_CG_UPDATE: launch_reduce<FASCIA_T_CG_UPDATE>(L, D, n, a, b, step); break;
  case FASCIA_T_PATCHES: launch_reduce<FASCIA_T_PATCHES>(L, D, n, a, b, step); break;
  case FASCIA_T_STRAIN: launch_reduce<FASCIA_T_STRAIN>(L, D, n, a, b, step); break;
  default: remember_error(L, cudaErrorInvalidValue, "reduction %d (no such terms)", (int)terms); break;
  }
}

// -------------------------------------------------------------- sequences --

static fascia_status cuda_record(fascia_launcher *L, int slot, void (*body)(void *arg), void *arg) {
  FASCIA_CHECK(slot >= 0 && slot < FASCIA_LAUNCH_SLOTS, L->ctx, FASCIA_ERR_ARGUMENT, "launcher: bad slot %d", slot);
  REFUSE_WHILE_RECORDING(L, "recording");
  // as the emulation: the old sequence is gone even if this one fails
  if (L->sequences[slot]) {
    cudaGraphExecDestroy(L->sequences[slot]);
    L->sequences[slot] = NULL;
  }
  // thread-local: other host threads may use CUDA meanwhile
  cudaError_t error = handled(cudaStreamBeginCapture(L->stream, cudaStreamCaptureModeThreadLocal));
  if (error == cudaSuccess) {
    L->recording = 1;
    body(arg);
    L->recording = 0;
    cudaGraph_t graph = NULL;
    error = handled(cudaStreamEndCapture(L->stream, &graph)); // ends the capture even when it failed
    if (L->error != cudaSuccess) { // a launch in body failed (that also invalidates the capture)
      if (graph) cudaGraphDestroy(graph);
      return FASCIA_FAIL(L->ctx, FASCIA_ERR_DEVICE, "cuda: recording a launch sequence failed: %s in %s",
                         cudaGetErrorString(L->error), L->error_where);
    }
    size_t nodes = 0;
    if (error == cudaSuccess) error = handled(cudaGraphGetNodes(graph, NULL, &nodes));
    if (error == cudaSuccess && nodes > 0) error = handled(cudaGraphInstantiate(&L->sequences[slot], graph, 0));
    if (graph) cudaGraphDestroy(graph); // the executable graph stands alone
  }
  if (error != cudaSuccess) {
    L->sequences[slot] = NULL;
    return FASCIA_FAIL(L->ctx, FASCIA_ERR_DEVICE, "cuda: recording a launch sequence failed: %s",
                       cudaGetErrorString(error));
  }
  return FASCIA_OK;
}

// A slot never recorded, or recorded empty, runs nothing (as the emulation).
static void cuda_replay(fascia_launcher *L, int slot) {
  if (slot < 0 || slot >= FASCIA_LAUNCH_SLOTS) {
    remember_error(L, cudaErrorInvalidValue, "replay of slot %d (no such slot)", slot);
    return;
  }
  if (!L->sequences[slot]) return;
  remember_error(L, handled(cudaGraphLaunch(L->sequences[slot], L->stream)), "replay of slot %d", slot);
}

static fascia_status cuda_finish(fascia_launcher *L) {
  REFUSE_WHILE_RECORDING(L, "finish");
  const cudaError_t error = handled(cudaStreamSynchronize(L->stream));
  if (L->error != cudaSuccess) return report_remembered(L);
  if (error != cudaSuccess) return report_wait(L, error, "waiting for the launches");
  return FASCIA_OK;
}

extern "C" const fascia_launcher_ops fascia_launcher_cuda = {
    "cuda",      cuda_create, cuda_destroy, cuda_name,   cuda_alloc,  cuda_release, cuda_upload, cuda_download,
    cuda_copy,   cuda_pin,    cuda_unpin,   cuda_send,   cuda_receive, cuda_kernel, cuda_reduce, cuda_record,
    cuda_replay, cuda_finish,
};
