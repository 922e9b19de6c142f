// gRPC-Web clients for the server that served this page (same origin). The transport is
// connect-web's gRPC-Web one (binary framing over fetch; server streams are read incrementally
// from the response body); messages are encoded and decoded by @bufbuild/protobuf from the
// code protoc-gen-es generated from proto/sportsim/v1.
import { createClient } from "@connectrpc/connect";
import { createGrpcWebTransport } from "@connectrpc/connect-web";
import { Billiards } from "../gen/sportsim/v1/billiards_pb.js";
import { Swing } from "../gen/sportsim/v1/swing_pb.js";
import { Server } from "../gen/sportsim/v1/common_pb.js";

export function makeClients(baseUrl) {
  const transport = createGrpcWebTransport({ baseUrl, useBinaryFormat: true });
  return {
    billiards: createClient(Billiards, transport),
    swing: createClient(Swing, transport),
    server: createClient(Server, transport),
  };
}
