"""Fast DDS settings for the controller interface process: a received sample's buffer is freed once it is taken.

rmw_fastrtps gives every DataReader a payload pool whose buffers keep the size of the largest sample they
held (history memory policy PREALLOCATED_WITH_REALLOC). After one 100,000-point goal (13.6 MB serialized) and one
such joint_trajectory message, the gateway process would keep 27 MB for good, for the next large one.

rmw_fastrtps sets that policy in code unless ``RMW_FASTRTPS_USE_QOS_FROM_XML=1``, which leaves every entity's
settings to Fast DDS's XML default profiles. The profile written here restores what rmw_fastrtps would set in
code (builtin discovery histories that grow, writers' history policy and publication mode, data sharing off; see
rmw_fastrtps_shared_cpp's participant, publisher, subscription, client and service creation) and changes one
thing: readers allocate each payload when a sample arrives and free it when the sample is taken (DYNAMIC).

Applied only with rmw_fastrtps_cpp, and only when the user gave Fast DDS no profiles or QoS switch of their own.
"""
from __future__ import annotations

import os
import tempfile
from collections.abc import MutableMapping
from pathlib import Path

_SWITCHES = ('RMW_FASTRTPS_USE_QOS_FROM_XML', 'FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')
_CWD_PROFILE = 'DEFAULT_FASTRTPS_PROFILES.xml'  # Fast DDS loads this from the working directory by itself

_PROFILE = """<?xml version="1.0" encoding="UTF-8"?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <participant profile_name="ur_sim_gateway_participant" is_default_profile="true">
    <rtps>
      <builtin>
        <readerHistoryMemoryPolicy>PREALLOCATED_WITH_REALLOC</readerHistoryMemoryPolicy>
        <writerHistoryMemoryPolicy>PREALLOCATED_WITH_REALLOC</writerHistoryMemoryPolicy>
      </builtin>
    </rtps>
  </participant>
  <data_writer profile_name="ur_sim_gateway_writer" is_default_profile="true">
    <qos>{publish_mode}
      <data_sharing><kind>OFF</kind></data_sharing>
    </qos>
    <historyMemoryPolicy>PREALLOCATED_WITH_REALLOC</historyMemoryPolicy>
  </data_writer>
  <data_reader profile_name="ur_sim_gateway_reader" is_default_profile="true">
    <qos>
      <data_sharing><kind>OFF</kind></data_sharing>
    </qos>
    <historyMemoryPolicy>DYNAMIC</historyMemoryPolicy>
  </data_reader>
</profiles>
"""


def profile_text(publication_mode: str | None) -> str:
    """The XML profile; `publication_mode` is RMW_FASTRTPS_PUBLICATION_MODE's value (rmw_fastrtps: unset or
    unknown is SYNCHRONOUS, AUTO leaves Fast DDS's default)."""
    mode = (publication_mode or '').strip()
    if mode == 'AUTO':
        kind = ''
    else:
        kind = 'ASYNCHRONOUS' if mode == 'ASYNCHRONOUS' else 'SYNCHRONOUS'
        kind = f'\n      <publishMode><kind>{kind}</kind></publishMode>'
    return _PROFILE.format(publish_mode=kind)


def applies(environ: MutableMapping[str, str], cwd: Path) -> bool:
    """Whether the profile is for this process: rmw_fastrtps_cpp (the default rmw) and nothing of the user's."""
    rmw = environ.get('RMW_IMPLEMENTATION', '') or 'rmw_fastrtps_cpp'
    return rmw == 'rmw_fastrtps_cpp' and not any(environ.get(k) for k in _SWITCHES) \
        and not (cwd / _CWD_PROFILE).exists()


def free_received_samples(environ: MutableMapping[str, str] | None = None) -> Path | None:
    """Point this process's Fast DDS at the profile (call before the first node is created). Returns the
    profile's file, which the caller removes once the nodes exist (Fast DDS reads it once), or None when the
    profile does not apply here."""
    env = os.environ if environ is None else environ
    if not applies(env, Path.cwd()):
        return None
    fd, name = tempfile.mkstemp(prefix='ur_sim_gateway_', suffix='.xml')
    with os.fdopen(fd, 'w') as f:
        f.write(profile_text(env.get('RMW_FASTRTPS_PUBLICATION_MODE')))
    env['FASTRTPS_DEFAULT_PROFILES_FILE'] = name
    env['RMW_FASTRTPS_USE_QOS_FROM_XML'] = '1'
    return Path(name)
