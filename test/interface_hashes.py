"""Reading installed rosidl type descriptions: the RIHS01 type hashes and message constants.

The hash of a type (REP 2011) covers field names, types and order of the type and every type it
refers to, but not constants or default values, so tests compare both separately with upstream.
"""
from __future__ import annotations

import json
from pathlib import Path

from ament_index_python.packages import get_package_share_directory


def type_hash(full_name: str) -> str:
    """The RIHS01 hash of `full_name` ('pkg/msg|srv|action/Name') from the installed type-description JSON."""
    pkg, kind, name = full_name.split('/')
    path = Path(get_package_share_directory(pkg)) / kind / f'{name}.json'
    assert path.is_file(), f'no generated type description for {full_name} at {path}'
    hashes = {h['type_name']: h['hash_string'] for h in json.loads(path.read_text())['type_hashes']}
    assert full_name in hashes, f'{path} has no hash for {full_name} (has {sorted(hashes)})'
    return hashes[full_name]


def constants_of(msg_class) -> dict:
    """All constants rosidl generated for a message class (name -> value), and nothing else."""
    meta = type(msg_class)
    return dict(getattr(meta, f'_{meta.__name__}__constants'))
