"""Contains all the data models used in inputs/outputs"""

from .bound import Bound
from .cell_in import CellIn
from .cell_out import CellOut
from .coordination import Coordination
from .database_state import DatabaseState
from .detection_in import DetectionIn
from .estimator_kind import EstimatorKind
from .evaluate_body import EvaluateBody
from .evaluate_request_by_id import EvaluateRequestById
from .evaluate_request_with_scenario import EvaluateRequestWithScenario
from .evaluate_response import EvaluateResponse
from .explain import Explain
from .fit_request import FitRequest
from .fit_response import FitResponse
from .fit_step import FitStep
from .fit_tolerance import FitTolerance
from .fov_spec_type_0 import FovSpecType0
from .fov_spec_type_0_shape import FovSpecType0Shape
from .fov_spec_type_1 import FovSpecType1
from .fov_spec_type_1_shape import FovSpecType1Shape
from .get_open_api_response_200 import GetOpenApiResponse200
from .grid import Grid
from .heading import Heading
from .health import Health
from .joint_report import JointReport
from .joint_stop import JointStop
from .no_go_spec import NoGoSpec
from .objective import Objective
from .observed import Observed
from .obstacle_kind_name import ObstacleKindName
from .obstacle_spec import ObstacleSpec
from .plan_out import PlanOut
from .plan_request import PlanRequest
from .plan_request_by_id import PlanRequestById
from .plan_request_with_scenario import PlanRequestWithScenario
from .plan_response import PlanResponse
from .point_out import PointOut
from .position_in import PositionIn
from .prior_kind import PriorKind
from .problem import Problem
from .scenario_list import ScenarioList
from .scenario_spec import ScenarioSpec
from .scenario_spec_sensor_types_type_0 import ScenarioSpecSensorTypesType0
from .scenario_stats import ScenarioStats
from .scenario_status import ScenarioStatus
from .scenario_summary import ScenarioSummary
from .sensor_in import SensorIn
from .sensor_path_in import SensorPathIn
from .sensor_score import SensorScore
from .sensor_type_spec import SensorTypeSpec
from .session_info import SessionInfo
from .session_request_by_id import SessionRequestById
from .session_request_with_scenario import SessionRequestWithScenario
from .session_settings import SessionSettings
from .source_rate import SourceRate
from .source_spec import SourceSpec
from .speed_spec import SpeedSpec
from .step_request import StepRequest
from .step_response import StepResponse
from .summary_stats import SummaryStats
from .target_in import TargetIn
from .track import Track
from .unexplained import Unexplained
from .zone_spec import ZoneSpec

__all__ = (
    "Bound",
    "CellIn",
    "CellOut",
    "Coordination",
    "DatabaseState",
    "DetectionIn",
    "EstimatorKind",
    "EvaluateBody",
    "EvaluateRequestById",
    "EvaluateRequestWithScenario",
    "EvaluateResponse",
    "Explain",
    "FitRequest",
    "FitResponse",
    "FitStep",
    "FitTolerance",
    "FovSpecType0",
    "FovSpecType0Shape",
    "FovSpecType1",
    "FovSpecType1Shape",
    "GetOpenApiResponse200",
    "Grid",
    "Heading",
    "Health",
    "JointReport",
    "JointStop",
    "NoGoSpec",
    "Objective",
    "Observed",
    "ObstacleKindName",
    "ObstacleSpec",
    "PlanOut",
    "PlanRequest",
    "PlanRequestById",
    "PlanRequestWithScenario",
    "PlanResponse",
    "PointOut",
    "PositionIn",
    "PriorKind",
    "Problem",
    "ScenarioList",
    "ScenarioSpec",
    "ScenarioSpecSensorTypesType0",
    "ScenarioStats",
    "ScenarioStatus",
    "ScenarioSummary",
    "SensorIn",
    "SensorPathIn",
    "SensorScore",
    "SensorTypeSpec",
    "SessionInfo",
    "SessionRequestById",
    "SessionRequestWithScenario",
    "SessionSettings",
    "SourceRate",
    "SourceSpec",
    "SpeedSpec",
    "StepRequest",
    "StepResponse",
    "SummaryStats",
    "TargetIn",
    "Track",
    "Unexplained",
    "ZoneSpec",
)
