// SPDX-License-Identifier: BSD-3-Clause
// Serialized samples as Cyclone itself writes them: idlc structs sent through a Writer and taken
// back as raw CDR, for the decoder tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <dds/dds.h>

namespace raymap::dds::test {

/// @brief A DDS domain for the tests of one process: 150 + pid % 40, so parallel test processes
/// rarely share one (the tests tolerate a stranger's endpoints: their topic names are their own).
std::uint32_t decoderTestDomain();

/// @brief Writes each of `samples` (idlc structs of `descriptor`) on `topic` in a participant of
/// decoderTestDomain(), reliable, and returns the serialized bytes a raw reader got for each, in
/// order (with the encapsulation header). Empty when something failed (reported with
/// ADD_FAILURE).
std::vector<std::vector<std::byte>> cyclonesBytes(const char* topic,
                                                  const dds_topic_descriptor_t* descriptor,
                                                  const std::vector<const void*>& samples);

}  // namespace raymap::dds::test
