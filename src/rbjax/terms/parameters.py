"""The parameter layer: every parameter's name (with its unit), bounds and fitting transform.

Each model term (the ``Ball``, every damping law, the stiffening, the blocked-force
convention) is an equinox Module that declares the parameters of its fields in a class
attribute ``PARAMETERS = {field: Parameter(...)}`` (the declarations: :mod:`rbjax.terms.declare`)
(in the spirit of dynamax's ``ParameterProperties``, kept beside the pytree rather than inside
it). This module walks an impact (drop height, ball, model) and gives

- :func:`parameter_table`: the names, values and declarations of all its parameters, in one
  fixed order (the order of the pytree's leaves);
- :func:`to_vector` / :func:`from_vector`: the flat parameter vector and back (used by the
  fit, the sweeps and the sensitivities; jit-, vmap- and grad-safe);
- :func:`replace`: the impact with some named parameters replaced (tracers allowed);
- :func:`canonical_name`: a parameter name in any letter case → its declared name.

Names are unique across terms (the field names carry their units: ``youngs_Pa``,
``damping_Ns_per_m``), so a name alone says which term a parameter belongs to.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from .ball import JIS_RUBBER_BALL, Ball
from .declare import HEIGHT, Parameter, declarations
from .model import Model


def _leaf_entries(height_m, ball, model):
    """(name, declaration, path) of every continuous parameter of the impact, in leaf order."""
    tree = (height_m, ball, model)
    leaves, _ = jax.tree_util.tree_flatten_with_path(tree)
    out = []
    for path, _leaf in leaves:
        if len(path) == 1:  # the height
            out.append(("height_m", HEIGHT, path))
            continue
        owner = tree
        for key in path[:-1]:
            owner = _step(owner, key)
        key = path[-1]
        if not isinstance(key, jax.tree_util.GetAttrKey):
            raise TypeError(
                f"parameter at {jax.tree_util.keystr(path)} is not a named field of a term"
            )
        spec = declarations(owner).get(key.name)
        if spec is None:
            raise TypeError(
                f"{type(owner).__name__}.{key.name} is an array field without a declaration: add "
                f"it to {type(owner).__name__}.PARAMETERS (or make it static)"
            )
        out.append((key.name, spec, path))
    names = [n for n, _, _ in out]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise ValueError(
            f"parameter names {dupes} occur in more than one term; names must be unique"
        )
    return out


def _step(node, key):
    if isinstance(key, jax.tree_util.GetAttrKey):
        return getattr(node, key.name)
    if isinstance(key, jax.tree_util.SequenceKey):
        return node[key.idx]
    if isinstance(key, jax.tree_util.DictKey):
        return node[key.key]
    raise TypeError(f"cannot follow {key!r}")


@dataclasses.dataclass(frozen=True)
class ParameterInfo:
    """One row of :func:`parameter_table`."""

    name: str
    value: float
    spec: Parameter

    @property
    def unit(self) -> str:
        return self.spec.unit


def parameter_names(
    height_m: ArrayLike = 1.0, ball: Ball | None = None, model: Model | None = None
) -> tuple[str, ...]:
    """Names of the continuous parameters of an impact, in vector order.

    Args:
        height_m: drop height h_D (m); its value does not change the names.
        ball: the :class:`~rbjax.terms.ball.Ball` (default ``JIS_RUBBER_BALL``).
        model: the :class:`~rbjax.terms.model.Model` (default ``Model()``).

    Returns:
        The names, ``"height_m"`` first, then the ball's and the model's parameters in the
            order of the pytree's leaves (the order of :func:`to_vector`).

    Raises:
        TypeError: a term with an array field that its ``PARAMETERS`` do not declare.
        ValueError: a parameter name that occurs in more than one term.
    """
    ball, model = _defaults(ball, model)
    return tuple(n for n, _, _ in _leaf_entries(height_m, ball, model))


def parameter_table(
    height_m: ArrayLike = 1.0, ball: Ball | None = None, model: Model | None = None
) -> tuple[ParameterInfo, ...]:
    """Name, value and declaration of every parameter of the impact (scalar values).

    Args:
        height_m: drop height h_D (m), a scalar (default 1 m).
        ball: the :class:`~rbjax.terms.ball.Ball` with scalar fields (default
            ``JIS_RUBBER_BALL``).
        model: the :class:`~rbjax.terms.model.Model` with scalar parameters (default
            ``Model()``).

    Returns:
        One :class:`ParameterInfo` (name, value as a float, declaration) per parameter, in
            :func:`parameter_names` order.

    Raises:
        TypeError: a term with an array field that its ``PARAMETERS`` do not declare.
        ValueError: a parameter that is not a scalar (an array of values: the message names
            the field and its shape), or a parameter name that occurs in more than one term.
    """
    ball, model = _defaults(ball, model)
    tree = (height_m, ball, model)
    rows = []
    for name, spec, path in _leaf_entries(height_m, ball, model):
        owner, node = None, tree
        for key in path:
            owner, node = node, _step(node, key)
        value = np.asarray(node)
        if value.ndim != 0:
            field = name if len(path) == 1 else f"{type(owner).__name__}.{name}"
            raise ValueError(
                f"{field}={np.array2string(value, threshold=6, edgeitems=2)} is an array of "
                f"shape {value.shape}: parameter_table takes one impact, a scalar per parameter "
                "(shape ())"
            )
        rows.append(ParameterInfo(name, float(value), spec))
    return tuple(rows)


def declaration(name: str, ball=None, model=None) -> Parameter:
    """The declaration of parameter ``name`` in the impact of ``ball`` and ``model``."""
    ball, model = _defaults(ball, model)
    for n, spec, _ in _leaf_entries(1.0, ball, model):
        if n == name:
            return spec
    raise ValueError(
        f"parameter {name!r} is not known; valid: {', '.join(parameter_names(1.0, ball, model))}"
    )


def _defaults(ball, model):

    return (JIS_RUBBER_BALL if ball is None else ball), (Model() if model is None else model)


def to_vector(height_m, ball, model) -> jnp.ndarray:
    """The impact's parameters as one float64 vector, in :func:`parameter_names` order."""
    leaves = jax.tree_util.tree_leaves((height_m, ball, model))
    return jnp.stack([jnp.asarray(x, dtype=jnp.float64) for x in leaves])


def from_vector(vector, ball, model):
    """(height, ball, model) with the values of ``vector`` (the template gives the structure)."""
    leaves, treedef = jax.tree_util.tree_flatten((0.0, ball, model))
    n = len(leaves)
    if jnp.shape(vector) != (n,):
        raise ValueError(
            f"parameter vector has shape {jnp.shape(vector)}; expected ({n},) for "
            f"{parameter_names(1.0, ball, model)}"
        )
    return jax.tree_util.tree_unflatten(treedef, [vector[i] for i in range(n)])


def canonical_name(name: str, ball=None, model=None) -> str:
    """The parameter called ``name`` in any letter case (``youngs_pa`` → ``youngs_Pa``)."""
    valid = parameter_names(1.0, ball, model)
    for v in valid:
        if v.lower() == str(name).lower():
            return v
    raise ValueError(f"parameter {name!r} is not known; valid (any case): {', '.join(valid)}")


def replace(params: Mapping, height_m, ball, model):
    """(height, ball, model) with the named parameters of ``params`` replaced (arrays or tracers).

    ``height_m`` may be ``None`` when ``params`` holds ``height_m``.
    """
    params = dict(params)
    height_m = params.pop("height_m", height_m)
    entries = {n: path for n, _, path in _leaf_entries(1.0, ball, model)}
    unknown = sorted(set(params) - set(entries))
    if unknown:
        raise ValueError(f"parameters {unknown} are not known; valid: {', '.join(entries)}")
    tree = (1.0, ball, model)
    for name, value in params.items():

        def where(t, path=entries[name]):
            node = t
            for key in path:
                node = _step(node, key)
            return node

        tree = eqx.tree_at(where, tree, value)
    _recheck(tree[1])
    _recheck(tree[2])
    return height_m, tree[1], tree[2]


def _recheck(node) -> None:
    """Run the ``__check_init__`` of every term in a pytree (``eqx.tree_at`` skips them);
    each skips traced values, so this checks concrete replacements only."""
    if isinstance(node, eqx.Module):
        check = getattr(type(node), "__check_init__", None)
        if check is not None:
            check(node)
        for field in dataclasses.fields(node):
            _recheck(getattr(node, field.name))
    elif isinstance(node, (tuple, list)):
        for item in node:
            _recheck(item)
