/* SPDX-License-Identifier: BSD-3-Clause */
/* OpenCL program of height-map generation: the entry points of kernels/device/heightmap_kernels.h
 * (the CUDA build compiles the same header). Built with -cl-std=CL1.2. */

/* The CPU generator computes heights without fused multiply-add; so must the device, for the
 * generators to agree bit for bit (the CUDA build passes --fmad=false). */
#pragma OPENCL FP_CONTRACT OFF

#include "kernels/device/heightmap_kernels.h"
