/* SPDX-License-Identifier: BSD-3-Clause */
/* OpenCL program of the device planner: the entry points of kernels/device/plan_kernels.h (the
 * CUDA build compiles the same header). Built with -cl-std=CL1.2 and -DRM_PLAN_GROUP=<work-group
 * size>. */

/* The host planner walks the same regions in IEEE float without fused multiply-add; contracting
 * a * b + c here could move a region crossing by one rounding step and give another plan. */
#pragma OPENCL FP_CONTRACT OFF

#include "kernels/device/plan_kernels.h"
