"""Tone-mapping operators: equinox Modules, a registry and the ``tonemap`` dispatcher.

Numeric contract: input is linear-light RGB ``(..., H, W, 3)`` (relative, or cd/m² where an
operator says so); output is display-referred linear RGB, nominally [0, 1], before display
encoding (:mod:`hdrjax.display`). Every operator works under ``jit``, ``vmap`` and ``grad``.
"""

from ._ashikhmin2002 import Ashikhmin2002 as Ashikhmin2002
from ._base import (
    ENTRY_POINT_GROUP as ENTRY_POINT_GROUP,
    AbstractLuminanceCurve as AbstractLuminanceCurve,
    AbstractOperator as AbstractOperator,
    ParameterInfo as ParameterInfo,
    StatisticsSettings as StatisticsSettings,
    apply_in_space as apply_in_space,
    bound_stats as bound_stats,
    fill as fill,
    get_operator as get_operator,
    make_operator as make_operator,
    measure_in_space as measure_in_space,
    operator_names as operator_names,
    parameter as parameter,
    parameter_info as parameter_info,
    parameter_names as parameter_names,
    register as register,
    tonemap as tonemap,
    weights_field as weights_field,
)
from ._budak2005 import (
    AbstractContrastSpace as AbstractContrastSpace,
    Budak2005 as Budak2005,
    ConeOpponentSpace as ConeOpponentSpace,
)
from ._chiu1993 import Chiu1993 as Chiu1993
from ._classic import (
    Exponential as Exponential,
    ExponentiationMapping as ExponentiationMapping,
    Filmic as Filmic,
    Gamma as Gamma,
    Logarithmic as Logarithmic,
    LogarithmicMapping as LogarithmicMapping,
    Normalisation as Normalisation,
    Reinhard2004 as Reinhard2004,
    Schlick1994 as Schlick1994,
    Simple as Simple,
)
from ._drago2003 import Drago2003 as Drago2003
from ._durand2002 import Durand2002 as Durand2002
from ._fattal2002 import Fattal2002 as Fattal2002
from ._ferradans2011 import Ferradans2011 as Ferradans2011
from ._ferwerda1996 import Ferwerda1996 as Ferwerda1996
from ._kimkautz2008 import KimKautz2008 as KimKautz2008
from ._krawczyk2005 import Krawczyk2005 as Krawczyk2005
from ._kuang2007 import Kuang2007 as Kuang2007
from ._linear import (
    Q_FACTOR as Q_FACTOR,
    Linear as Linear,
    ev100_luminance as ev100_luminance,
    saturation_luminance as saturation_luminance,
)
from ._lischinski2006 import Lischinski2006 as Lischinski2006
from ._mai2011 import Mai2011 as Mai2011
from ._mantiuk2006 import Mantiuk2006 as Mantiuk2006
from ._mantiuk2008 import Mantiuk2008 as Mantiuk2008
from ._paris2011 import Paris2011 as Paris2011
from ._pattanaik2000 import (
    AdaptationState as AdaptationState,
    Pattanaik2000 as Pattanaik2000,
    pattanaik2000_sequence as pattanaik2000_sequence,
)
from ._reinhard2002 import Reinhard2002 as Reinhard2002
from ._reinhard2002_local import (
    Reinhard2002Auto as Reinhard2002Auto,
    Reinhard2002Local as Reinhard2002Local,
)
from ._reinhard2005 import Reinhard2005 as Reinhard2005
from ._tabulated import Tabulated as Tabulated
from ._time import (
    AbstractTimeDependentOperator as AbstractTimeDependentOperator,
    time_dependent_names as time_dependent_names,
)
from ._tumblin import Tumblin1999 as Tumblin1999, TumblinReinhard as TumblinReinhard
from ._tumblin_rushmeier1993 import TumblinRushmeier1993 as TumblinRushmeier1993
from ._vanhateren2006 import (
    ConeState as ConeState,
    VanHateren2006 as VanHateren2006,
    vanhateren2006_sequence as vanhateren2006_sequence,
)
from ._view_transforms import (
    AcesHill as AcesHill,
    AcesNarkowicz2015 as AcesNarkowicz2015,
    AgX as AgX,
    Hable2010 as Hable2010,
    Lottes2016 as Lottes2016,
    PbrNeutral as PbrNeutral,
    Uchimura2017 as Uchimura2017,
)
from ._ward1994 import Ward1994 as Ward1994
from ._ward1997 import Ward1997 as Ward1997
