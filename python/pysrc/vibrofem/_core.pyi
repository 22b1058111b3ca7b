# The compiled half (python/src/lib.rs): used through the typed Python half only.
from typing import Any

def __getattr__(name: str) -> Any: ...
