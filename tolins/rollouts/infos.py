"""One env's ``info`` inside a vector env's batched ``infos``, read on demand."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any


class InfoRow(Mapping[str, Any]):
    """Env ``index``'s entries of gymnasium's batched ``infos``: the keys whose ``_key``
    mask holds ``index``, each read as ``infos[key][index]`` when asked for (a nested
    batched dict as its own row). It reads as the single env's ``info`` dict would."""

    def __init__(self, infos: Mapping[str, Any], index: int) -> None:
        self._infos, self._index = infos, index

    def _present(self, key: str) -> bool:
        if key.startswith("_") or key not in self._infos:
            return False
        mask = self._infos.get(f"_{key}")
        return mask is not None and bool(mask[self._index])

    def __getitem__(self, key: str) -> Any:
        if not self._present(key):
            raise KeyError(key)
        value = self._infos[key]
        return InfoRow(value, self._index) if isinstance(value, Mapping) else value[self._index]

    def __iter__(self) -> Iterator[str]:
        return (key for key in self._infos if self._present(key))

    def __len__(self) -> int:
        return sum(1 for _ in self)


def info_dict(infos: Mapping[str, Any], index: int) -> dict[str, Any]:
    """Env ``index``'s entries of the batched ``infos`` as a plain dict (nested ones too)."""
    row = {}
    for key, value in InfoRow(infos, index).items():
        row[key] = info_dict(infos[key], index) if isinstance(value, InfoRow) else value
    return row
