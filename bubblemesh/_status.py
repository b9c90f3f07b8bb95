"""One table of the kernels' status codes and one way to turn them into exceptions.

Every kernel returns a status: 0 or a positive code to say how it stopped, a
negative code for a failure; ``raise_for`` turns a failure into a
``GeometryError`` (the input is at fault) or a ``MeshingError`` (an internal
bound or invariant).
"""

from .errors import GeometryError, MeshingError

OK = 0

# failures of the triangulation kernels
ERR_NOT_STAR = -2
ERR_CAPACITY = -3
ERR_WALK = -4
ERR_COLLINEAR = -5
ERR_VERTEX_ON_SEGMENT = -6
ERR_RECOVERY = -7
ERR_STACK = -8
ERR_SEGMENTS_CROSS = -9

# the §2 insertion loop's stops (positive) and failure
STOP_POPULATION = 1  # eq. 6 reached
STOP_MAX_INSERTIONS = 2  # the caller's max_insertions reached
NEED_CAPACITY = 3  # arrays full: the caller grows them and resumes
CHUNK_DONE = 4  # a progress chunk is done: the caller reports and resumes
ERR_EMPTY_QUEUE = -20

MESSAGES = {
    ERR_NOT_STAR: "cavity is not star-shaped (internal invariant failed)",
    ERR_CAPACITY: "triangle capacity exceeded",
    ERR_WALK: "point location walk exceeded its bound",
    ERR_COLLINEAR: "all points are collinear (or fewer than 3 distinct points)",
    ERR_VERTEX_ON_SEGMENT: "a vertex lies on a segment",
    ERR_RECOVERY: "segment recovery exceeded its flip bound",
    ERR_STACK: "flip stack exceeded its bound",
    ERR_SEGMENTS_CROSS: "two segments cross",
    ERR_EMPTY_QUEUE: "priority queue ran empty",
}

_INPUT_FAULTS = (ERR_COLLINEAR, ERR_VERTEX_ON_SEGMENT, ERR_SEGMENTS_CROSS)


def raise_for(status: int, what: str, where: str = "") -> None:
    """Raise the exception for a failed kernel ``status`` (negative): ``what``
    names the stage, ``where`` (e.g. " (segment 3)") the place."""
    message = f"{what}: {MESSAGES.get(status, f'status {status}')}{where}"
    if status in _INPUT_FAULTS:
        raise GeometryError(message)
    raise MeshingError(message)
