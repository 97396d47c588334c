"""Which DXF layer plays which role: walls, doors, windows, floor or ignored.

Users name layers with ``--walls/--doors/--windows/--ignore`` globs
(fnmatch, case-insensitive). Without them, roles are guessed from the names
architects commonly use, in English, German, French, Spanish, Italian,
Portuguese, Dutch, Polish, Czech, Russian, Chinese, Japanese and Korean, and in the US National CAD
Standard (``A-WALL``, ``A-DOOR``, ``A-GLAZ``, ``A-COLS``, ``A-FURN`` ...)
and their numbered variants; zone and space polygons (``Zone``, ``Space``,
``Room``, ``Pieces``, ``Raum``) give the free space like a floor layer;
facade contours are walls; virtual partitions are ignored.
"""

from __future__ import annotations

import fnmatch
import re
import unicodedata
from collections.abc import Iterable

#: Roles, in the order they are reported.
ROLES = ("walls", "doors", "windows", "floor", "ignore")

# Whole-word patterns on the normalised layer name (lower case, accents
# folded, split on punctuation, digits and camelCase). Checked in order:
# annotation words win over everything (an "A-WALL-TEXT" layer holds text),
# doors before windows before walls (a "glass door" is a door, a "curtain
# wall" is glass). Compound words ending in a wall ("innerwall",
# "Staircase_outertwall", "Innenwand", "Trennwaende") are walls, a
# "curtainwall" or "Glaswand" glass.
_IGNORE_FIRST = r"""
    text|texts|txt|texte|texto|testo|testi|tekst|anno|annotation|notes?|dims?|dimensions?|dimension
    |cotas?|cotation|cotations?|quotas?|quote|bemassung|bemasung|masse|maatvoering
    |patt|pattern|patterns?|tiles?|tiling|carrelage|fliesen|baldosas?|piastrelle
    |furn|furniture|mobilier|moebel|mobel|muebles?|mobiliario|arredo|arredi|meubilair|meubels?
    |eqpm|equipment|appliances?|fixtures?|plumbing|plmb|sanitary|sanitaire|elec|electrical|hvac|mech
    |grid|axis|axes|achsen?|ejes?|title|titleblock|frame|viewport|vport|defpoints|hidden|cancel
    |projection|roof|ceiling|clng|plafond|techo|decke|trees?|plants?|landscape|symbols?|iden|tags?
    |names?|labels?|noms?|nummern?|numbers?|numeros?
    |virtual|virtuals|virtuel|virtuelle|virtuell|virtuale|notional|imaginary
    |hatch|hatches|hatching|schraffur|schraffuren|hachures?|hachurage|tramas?|retini|arcering
    |luft|lueftung|luftung|ventilation|background|hintergrund|hintergrundbild|underlay|xref|images?
"""
_DOORS = r"doors?|door|dr|porte|portes|tuer|tur|tueren|turen|puertas?|porta|porte|deur|deuren|portas?|drzwi|dvere|dveri"
_WINDOWS = r"""
    windows?|wndw|glaz|glazing|glass|crystal|cristal|cristales|vitre|vitres|vitrage|fenetres?
    |fenster|glas|verglasung|ventanas?|vidrio|finestr[ae]|vetro|vetri|ramen|raam|janelas?|vidro|curtain|cwmg
    |curtainwalls?|glasswalls?|glaswand|glaswaende|glaswande|[a-z]+fenster|okna|okno|okien
    |serramenti|serramento
"""
_WALLS = r"""
    walls?|wall|wand|waende|wande|mauer|mauern|murs?|muros?|muri|muur|muren|wanden|pared|paredes|parete|pareti|parede|paredes
    |partitions?|prtn|cloisons?|tabiques?|tramezz[io]|structure|structural|struct|strs|tragwerk
    |columns?|cols?|colonnes?|colonnas?|columnas?|pilier|piliers|pilar|pilares|pilastr[io]|poteaux?|stuetzen?|stutzen?|kolom|kolommen
    |core|beton|concrete|hormigon|masonry|maconnerie|mauerwerk|muratura|murature|muratur[ae]|sciany|sciana|scianki
    |zdi|zed|zdivo|steny|stena|muro|muros|murs?|alvenaria|metselwerk
    |facades?|fassaden?|fachadas?|facciata|facciate|gevel|gevels|envelope|shell
    |[a-z]+walls?|[a-z]+wand|[a-z]+waende|[a-z]+wande
"""
_FLOOR = r"""
    flooring|floors?|flor|sol|sols|dallage|revetement|suelos?|pavimentos?|piso|boden|fussboden|vloer|paving
    |zones?|zona|zonas|spaces?|espaces?|espacios?|rooms?|pieces?|raum|raume|raeume|stanze?|habitaciones?|locaux|local
"""


def _rx(alternatives: str) -> re.Pattern:
    words = "".join(alternatives.split())
    return re.compile(rf"^(?:{words})$")


_GUESS_ORDER = [
    ("ignore", _rx(_IGNORE_FIRST)),
    ("doors", _rx(_DOORS)),
    ("windows", _rx(_WINDOWS)),
    ("walls", _rx(_WALLS)),
    ("floor", _rx(_FLOOR)),
]


def _latin_base(c: str) -> str:
    """A Latin letter without its accents ("é" -> "e"); any other character as it is."""
    base = "".join(x for x in unicodedata.normalize("NFKD", c) if not unicodedata.combining(x))
    return base if base.isascii() else c


def tokens(layer: str) -> list[str]:
    """Words of a layer name: "A-WALL-Full", "Wände", "outerWalls", "Стены" -> lower-case words.

    Latin letters are folded to ASCII (accents dropped); other scripts keep
    their letters (Cyrillic lower-cased; Chinese, Japanese and Korean names,
    written without spaces, stay one word each: :data:`_CJK_WORDS` looks
    inside them)."""
    # Fold the accents of Latin letters (German umlauts also commonly appear
    # spelled "ue", "ae", "oe"); other scripts' marks stay (the voicing mark
    # of the katakana ド, the breve of the Cyrillic й).
    folded = "".join(_latin_base(c) for c in layer.replace("ß", "ss"))
    split = re.sub(r"([a-z])([A-Z])", r"\1 \2", folded)
    return [w for w in re.split(r"[\W\d_]+", split.lower()) if w]


#: Words of Russian layer names, by role, matched as the start of a word
#: (Russian inflects: "стена", "стены", "стен" are all walls), or whole
#: where they end in "$" (short words that begin others: "пол", floor, and
#: "полки", shelves). Checked in the role order of :data:`_GUESS_ORDER`.
_CYRILLIC_STEMS = {
    "ignore": ("текст", "надпис", "подпис", "размер", "оси$", "ось$", "осев", "штрих", "мебел", "оборуд", "сантех",
               "электр", "обознач", "штамп", "рамк", "сетк", "виртуал"),
    "doors": ("двер", "дверн"),
    "windows": ("окн", "окон", "витраж", "остекл", "стекл"),
    "walls": ("стен", "перегород", "колонн", "пилон", "несущ", "кладк", "фасад", "конструкц"),
    "floor": ("помещен", "комнат", "пол$", "полы$", "зона$", "зоны$"),
}

#: Words of Chinese, Japanese and Korean layer names, by role: found
#: anywhere inside a name (these scripts write no spaces between words).
#: Checked in the role order of :data:`_GUESS_ORDER`, so an annotation
#: layer of doors ("门墙窗标注": doors, walls, windows, dimensions) is
#: ignored, a curtain wall ("幕墙") is glass, a door-and-window layer a door.
_CJK_WORDS = {
    "ignore": ("文字", "文本", "标注", "尺寸", "轴", "填充", "家具", "图框", "图签", "面积", "说明", "符号", "标高",
               "索引", "设备", "洁具", "绿化", "植物", "寸法", "通り芯", "通芯", "ハッチ", "図枠", "器具",
               "문자", "치수", "가구", "해치", "중심선", "도곽", "설비"),
    "doors": ("门", "門", "扉", "ドア", "문"),
    "windows": ("幕墙", "窗", "玻璃", "窓", "サッシ", "ガラス", "창", "유리"),
    "walls": ("墙", "牆", "壁", "柱", "隔断", "结构", "砌体", "混凝土", "躯体", "벽", "기둥", "칸막이", "구조"),
    "floor": ("房间", "空间", "地面", "部屋", "공간", "바닥"),
}


def _script_word(role: str, word: str) -> bool:
    """Whether ``word`` (not Latin) is one of ``role``'s words in another script."""
    if any("\u0400" <= c <= "\u04ff" for c in word):
        return any(word == st[:-1] if st.endswith("$") else word.startswith(st) for st in _CYRILLIC_STEMS[role])
    return any(w in word for w in _CJK_WORDS[role])


_VIRTUAL = re.compile(r"^(?:virtual|virtuals|virtuel|virtuelle|virtuell|virtuale|notional|imaginary)$")

#: What each guessed role means for the map, for ``mapkit layers``.
_MEANING = {
    "ignore": "not building geometry",
    "doors": "door drawings: openings in walls",
    "windows": "windows or glass",
    "walls": "walls: block the robot and the view",
    "floor": "outlines of the floor or of rooms: free space",
}


def explain_role(layer: str) -> tuple[str | None, str]:
    """Role guessed from a layer's name and why: ``("walls", "'structure': walls ...")``.

    Words are matched whole, numbers and punctuation ignored, so AIA/NCS
    names and their numbered variants read alike (``A-WALL``, ``A-210 G -
    Existing Structure 4``, ``A-320G - Permanent Solid Partitions 12``).
    A virtual partition (``I-321G - Virtual Partition 18``) marks a zone
    on the plan, not a wall on site: ignored, it blocks nothing."""
    words = tokens(layer)
    for role, rx in _GUESS_ORDER:
        hit = next((w for w in words if rx.match(w) or (not w.isascii() and _script_word(role, w))), None)
        if hit is not None:
            if _VIRTUAL.match(hit):
                return role, f"'{hit}': a partition drawn for zoning, not built: blocks nothing"
            return role, f"'{hit}': {_MEANING[role]}"
    return None, "no known word in the name"


_ZONE = re.compile(r"""^(?:zones?|zona|zonas|spaces?|espaces?|espacios?|rooms?|pieces?|raum|raume|raeume|stanze?
                     |habitaciones?|locaux|local)$""", re.X)


def is_zone_layer(layer: str) -> bool:
    """Whether a layer's name says it holds room or space polygons (not one floor outline)."""
    return any(_ZONE.match(w) for w in tokens(layer))


def guess_role(layer: str) -> str | None:
    """Role guessed from a layer's name, or None when the name says nothing."""
    return explain_role(layer)[0]


def _matches(layer: str, globs: Iterable[str]) -> bool:
    name = layer.casefold()
    return any(fnmatch.fnmatchcase(name, g.casefold()) for g in globs)


def assign_roles(
    layers: Iterable[str],
    walls: list[str],
    doors: list[str],
    windows: list[str],
    ignore: list[str],
    floor: list[str] | None = None,
) -> dict[str, str | None]:
    """Role of every layer: "walls", "doors", "windows", "floor", "ignore", or None (unknown).

    Explicit globs win. A role given explicitly is not guessed for other
    layers (``--walls W`` means "only W are walls"); roles not given are
    still guessed. ``ignore`` globs beat everything.
    """
    explicit = {"walls": walls, "doors": doors, "windows": windows, "floor": floor or []}
    given = {role for role, globs in explicit.items() if globs}
    out: dict[str, str | None] = {}
    for layer in layers:
        if _matches(layer, ignore):
            out[layer] = "ignore"
            continue
        role = next((r for r in ("doors", "windows", "walls", "floor") if _matches(layer, explicit[r])), None)
        if role is None:
            guessed = guess_role(layer)
            # "--walls W" means only W are walls: a layer merely named like a
            # wall is then ignored, not guessed.
            role = "ignore" if guessed in given else guessed
        out[layer] = role
    return out


def unmatched_globs(layers: Iterable[str], **globs_by_role: list[str]) -> list[str]:
    """The user's globs that match no layer (probably typos), as "--role glob"."""
    layers = list(layers)
    missing = []
    for role, globs in globs_by_role.items():
        for g in globs:
            if not any(_matches(layer, [g]) for layer in layers):
                missing.append(f"--{role} {g}")
    return missing
