/* SPDX-License-Identifier: BSD-3-Clause */
/* OpenCL program of the NDT-OM / NDT-TM integration: the entry points of
 * kernels/device/integrate_ndt_kernels.h (the CUDA build compiles the same header). Built with
 * -cl-std=CL1.2; the host defines RM_HAVE_INT64_ATOMICS when the device has
 * cl_khr_int64_base_atomics. */

/* The host walks the same spans in IEEE float without fused multiply-add; contracting a * b + c
 * here could move a region crossing by one rounding step (the CUDA build passes --fmad=false). */
#pragma OPENCL FP_CONTRACT OFF

#include "kernels/device/integrate_ndt_kernels.h"
