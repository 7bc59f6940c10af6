"""Where the bench keeps its stages: the config-hash stage cache (:mod:`.cache`: one
folder per stage, finished once its marker is there) and the checked reads of what a
stage wrote (:mod:`.integrity`: file digests, JSON and arrays that name the file,
episodes within what an episode can be)."""
