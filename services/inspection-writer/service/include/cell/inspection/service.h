// cell-inspection-writer's bus binding: Records (cell/inspection/records.h) behind
// cell/inspection/{request,reply}, and what it made durable announced on cell/inspection/stored.
#pragma once

#include "cell/bus/bus.h"
#include "cell/idl/inspection.h"
#include "cell/inspection/records.h"

namespace cell::inspection {

class Service {
 public:
  Service(bus::Participant& p, Records& records);

 private:
  cell::InspectionReply Handle(const cell::InspectionRequest& r);
  Records& records_;
  bus::Writer<cell::InspectionStored> stored_;
  bus::Server<cell::InspectionRequest, cell::InspectionReply> server_;  // last: it calls Handle
};

}  // namespace cell::inspection
