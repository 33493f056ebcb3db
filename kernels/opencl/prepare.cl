/* SPDX-License-Identifier: BSD-3-Clause */
/* OpenCL program of the device's ray preparation: the entry points of
 * kernels/device/prepare_kernels.h (the CUDA build compiles the same header). Double precision, as
 * the host prepares rays: built only for a device with cl_khr_fp64, with -cl-std=CL1.2 and
 * -DRM_PLAN_GROUP=<work-group size>. */

#pragma OPENCL EXTENSION cl_khr_fp64 : enable

/* The host prepares in IEEE double without fused multiply-add; a contracted a * b + c could move
 * a ray's end by one rounding step into another voxel. */
#pragma OPENCL FP_CONTRACT OFF

#include "kernels/device/prepare_kernels.h"
