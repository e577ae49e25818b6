#!/usr/bin/env python3
"""Reads an MCAP file pinsight wrote (`--mcap`) with the official Python
readers (`mcap`, `mcap-protobuf-support`) and prints what a Foxglove user
would see, as one JSON object: per topic the schema name and encoding, the
message count, the first and last log_time, the field names of the first
message, and for the Foxglove types the decoded annotation counts.

    python3 tests/python/read_results_mcap.py FILE
"""

import json
import sys

from mcap.decoder import DecoderFactory as McapDecoderFactory
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory


class JsonDecoderFactory(McapDecoderFactory):
    """JSON messages (the `mcap` package decodes only what a factory names)."""

    def decoder_for(self, message_encoding, schema):
        return json.loads if message_encoding == "json" else None


def fields(msg):
    return sorted(f.name for f, _ in msg.ListFields()) if hasattr(msg, "ListFields") else sorted(msg)


def main(path):
    topics = {}
    annotations = []
    images = []
    statuses = []
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory(), JsonDecoderFactory()])
        header = reader.get_header()
        for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
            t = topics.setdefault(
                channel.topic,
                {
                    "schema": schema.name if schema else None,
                    "schema_encoding": schema.encoding if schema else None,
                    "message_encoding": channel.message_encoding,
                    "count": 0,
                    "first_ns": message.log_time,
                    "fields": None,
                },
            )
            t["count"] += 1
            t["last_ns"] = message.log_time
            if t["fields"] is None:
                t["fields"] = fields(decoded)
            if schema and schema.name == "pinsight.Inspection":
                statuses.append(decoded["status"])
            if schema and schema.name == "foxglove.ImageAnnotations":
                annotations.append(
                    {
                        "circles": len(decoded.circles),
                        "circle_fields": fields(decoded.circles[0]) if decoded.circles else [],
                        "point_types": [p.type for p in decoded.points],
                        "points": [len(p.points) for p in decoded.points],
                        "texts": [x.text for x in decoded.texts],
                        "stamp": [decoded.timestamp.seconds, decoded.timestamp.nanos],
                    }
                )
            if schema and schema.name == "foxglove.CompressedImage" and channel.message_encoding == "protobuf":
                images.append({"frame_id": decoded.frame_id, "format": decoded.format, "bytes": len(decoded.data)})
    print(json.dumps({"library": header.library, "topics": topics, "annotations": annotations, "images": images, "statuses": statuses}))


if __name__ == "__main__":
    main(sys.argv[1])
