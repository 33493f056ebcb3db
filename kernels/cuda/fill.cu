// SPDX-License-Identifier: BSD-3-Clause
// Fills device memory with a repeating multi-word pattern (a layer's clear value), which
// cudaMemset cannot do: occupancy clears to a float, voxel means to several words.
#include "kernels/cuda/launch.h"

namespace raymap::cuda {
namespace {

__global__ void fillWords(std::uint32_t* dst, unsigned long long words, FillPattern pattern) {
  const unsigned long long stride = static_cast<unsigned long long>(gridDim.x) * blockDim.x;
  for (unsigned long long i =
           static_cast<unsigned long long>(blockIdx.x) * blockDim.x + threadIdx.x;
       i < words; i += stride) {
    dst[i] = pattern.words[i % pattern.count];
  }
}

}  // namespace

cudaError_t launchFill(cudaStream_t stream, std::uint32_t* dst, std::size_t words,
                       const FillPattern& pattern) noexcept {
  if (words == 0) {
    return cudaSuccess;
  }
  if (pattern.count == 0 || pattern.count > 16 || words % pattern.count != 0) {
    return cudaErrorInvalidValue;
  }
  constexpr unsigned kThreads = 256;
  constexpr std::size_t kMaxBlocks = 4096;  // grid-stride beyond this
  const std::size_t wanted = (words + kThreads - 1) / kThreads;
  const auto blocks = static_cast<unsigned>(wanted < kMaxBlocks ? wanted : kMaxBlocks);
  fillWords<<<blocks, kThreads, 0, stream>>>(dst, words, pattern);
  return cudaGetLastError();
}

}  // namespace raymap::cuda
