"""Record insertion episodes to rerun ``.rrd`` files and replay them.

Sits at the edge of tolins: it reads envs and specs; only the top (the cli, the bench)
imports it.
"""

from tolins.record.recorder import RerunRecorder, RrdFile, record_episodes
from tolins.record.replay import RrdError, check_rrd, replay

__all__ = ["RerunRecorder", "RrdError", "RrdFile", "check_rrd", "record_episodes", "replay"]
