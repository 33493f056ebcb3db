#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes a rosbag2 SQLite (.db3) file from the topic and message stream write_bag.mjs sends.

Usage: write_db3.py OUT.db3 [--ros-distro humble] < stream

The stream (all integers little-endian): b"RMDB3\\n"; then records, each one tag byte:
  0x01 topic:   u32 length, JSON {name, type, serialization_format, offered_qos_profiles}
  0x02 message: u32 topic index (declaration order), i64 timestamp, u32 size, `size` CDR bytes
  0x00 end of stream (required: a stream cut short writes nothing).
The tables, index and schema row are those rosbag2_storage_default_plugins creates in Humble
(db schema version 3); topic ids are 1, 2, ... in declaration order, as its inserts assign them.
"""

import argparse
import json
import os
import sqlite3
import struct
import sys

SCHEMA_VERSION = 3
DDL = (
    "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);",
    "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,"
    "metadata TEXT NOT NULL);",
    "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
    "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);",
    "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
    "timestamp INTEGER NOT NULL, data BLOB NOT NULL);",
    "CREATE INDEX timestamp_idx ON messages (timestamp ASC);",
)
TOPIC_KEYS = ("name", "type", "serialization_format", "offered_qos_profiles")


class StreamError(Exception):
    pass


def read_exact(stream, size):
    data = stream.read(size)
    if len(data) != size:
        raise StreamError(f"stream ended inside a record ({len(data)} of {size} bytes)")
    return data


def write_db3(stream, connection, ros_distro):
    if read_exact(stream, 6) != b"RMDB3\n":
        raise StreamError("not a write_bag.mjs stream")
    cursor = connection.cursor()
    cursor.execute("BEGIN")
    for statement in DDL:
        cursor.execute(statement)
    cursor.execute(
        "INSERT INTO schema (schema_version, ros_distro) VALUES (?, ?)",
        (SCHEMA_VERSION, ros_distro),
    )
    topic_ids = []
    while True:
        tag = read_exact(stream, 1)[0]
        if tag == 0:
            break
        if tag == 1:
            (length,) = struct.unpack("<I", read_exact(stream, 4))
            topic = json.loads(read_exact(stream, length))
            cursor.execute(
                "INSERT INTO topics (name, type, serialization_format, offered_qos_profiles) "
                "VALUES (?, ?, ?, ?)",
                tuple(topic[key] for key in TOPIC_KEYS),
            )
            topic_ids.append(cursor.lastrowid)
        elif tag == 2:
            index, timestamp, size = struct.unpack("<IqI", read_exact(stream, 16))
            if index >= len(topic_ids):
                raise StreamError(f"message for undeclared topic index {index}")
            cursor.execute(
                "INSERT INTO messages (timestamp, topic_id, data) VALUES (?, ?, ?)",
                (timestamp, topic_ids[index], read_exact(stream, size)),
            )
        else:
            raise StreamError(f"unknown record tag {tag}")
    if stream.read(1):
        raise StreamError("bytes after the end record")
    cursor.execute("COMMIT")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out")
    parser.add_argument("--ros-distro", default="humble")
    args = parser.parse_args()
    if os.path.lexists(args.out):
        print(f"write_db3.py: {args.out} exists", file=sys.stderr)
        return 1
    connection = sqlite3.connect(args.out, isolation_level=None)
    try:
        write_db3(sys.stdin.buffer, connection, args.ros_distro)
        connection.close()
    except (StreamError, sqlite3.Error, ValueError, KeyError) as error:
        connection.close()
        os.remove(args.out)
        print(f"write_db3.py: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
