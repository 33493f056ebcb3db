// SPDX-License-Identifier: BSD-3-Clause
// MCAP chunk compression for the harness: zstd both ways through @foxglove/wasm-zstd, lz4 frames
// decompressed by @foxglove/wasm-lz4 and compressed by lz4js (wasm-lz4 has no compressor).

import decompressLz4 from "@foxglove/wasm-lz4";
import zstd from "@foxglove/wasm-zstd";
import lz4js from "lz4js";

/** Resolves once both WebAssembly modules are ready; call before any other function here. */
export async function loadCompression() {
  await zstd.isLoaded;
  await decompressLz4.isLoaded;
}

/** `decompressHandlers` for McapIndexedReader and McapStreamReader. */
export const kDecompressHandlers = Object.freeze({
  zstd: (data, size) => zstd.decompress(data, Number(size)),
  lz4: (data, size) => decompressLz4(data, Number(size)),
});

const kZstdLevel = 3;

function sameBytes(a, b) {
  return a.byteLength === b.byteLength && Buffer.compare(a, b) === 0;
}

/**
 * A `compressChunk` callback for McapWriter. Every compressed chunk is decompressed again with the
 * reader's handler and compared, so a compressor bug fails the write instead of making a fixture.
 * @param {"zstd" | "lz4"} compression
 */
export function makeChunkCompressor(compression) {
  const compress =
    compression === "zstd"
      ? (data) => zstd.compress(data, kZstdLevel)
      : (data) => lz4js.compress(data);
  return (chunkData) => {
    const compressedData = compress(chunkData);
    const roundTrip = kDecompressHandlers[compression](compressedData, chunkData.byteLength);
    if (!sameBytes(roundTrip, chunkData)) {
      throw new Error(`${compression} round trip of a ${chunkData.byteLength}-byte chunk differs`);
    }
    return { compression, compressedData };
  };
}
