// The client library's one translation from the DDS wire types (idl/mpdrig.idl, the generated
// C structs) to its values (rig_client.h, shadow_client.h). For the library's own files: a
// program sees only the values.
#pragma once

#include "clients/client/rig_client.h"
#include "clients/client/shadow_client.h"
#include "mpdrig.h"
#include "service/dds/dds.h"

namespace mpdrig::client {

// Every field; published_s from the sample's source timestamp (received_s is the caller's).
Sensors FromWire(const mpdrig_RigSensors& wire, const dds_sample_info_t& info);
Estimate FromWire(const mpdrig_RigEstimate& wire);
Profile FromWire(const mpdrig_PressureProfile& wire);
RigStatus FromWire(const mpdrig_RigStatus& wire);
ShadowStatus FromWire(const mpdrig_ShadowStatus& wire);

}  // namespace mpdrig::client
